/* rad_scene: writes the generated room of common/radiosity/rad_scenes.h
 * as a scene file, for benchmark jobs run through `gi render`.
 *
 *   rad_scene OUT.json [grid] [cubes] [cube side]     (defaults 4 2 0.25) */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_fs.h"
#include "radiosity/rad_scenes.h"

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: rad_scene OUT.json [grid] [cubes] [cube side]\n");
        return 2;
    }
    gi_rad_room_opts o = {argc > 2 ? atoi(argv[2]) : 4,
                          argc > 3 ? atoi(argv[3]) : 2,
                          argc > 4 ? atof(argv[4]) : 0.25,
                          {0, 0, 0},
                          10.0};
    if (o.grid < 1 || o.grid > 64 || o.cubes < 0 || o.cubes > 2 || !(o.cube > 0 && o.cube < 0.3)) {
        fprintf(stderr, "rad_scene: grid in [1, 64], cubes in [0, 2], side in (0, 0.3)\n");
        return 2;
    }
    char *text = gi_rad_room_scene(&o);
    gi_error err;
    int rc = gi_write_file_atomic(argv[1], text, strlen(text), &err);
    free(text);
    if (rc) {
        fprintf(stderr, "rad_scene: %s\n", err.msg);
        return 1;
    }
    return 0;
}
