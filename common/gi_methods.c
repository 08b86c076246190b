/* gi_methods: the registry of rendering methods. */
#include <string.h>

#include "gi_method.h"
#include "detp/detp.h"
#include "pt/pt.h"
#include "quadrature/quadrature.h"
#include "radiosity/rad.h"

static const gi_method *const all_methods[] = {
    &gi_method_pt,
    &gi_method_detp,
    &gi_method_quadrature,
    &gi_method_radiosity,
    NULL,
};

const gi_method *const *gi_methods(void) { return all_methods; }

const gi_method *gi_method_find(const char *name)
{
    if (!name)
        return NULL;
    for (const gi_method *const *m = all_methods; *m; m++)
        if (strcmp((*m)->name, name) == 0)
            return *m;
    return NULL;
}
