/* gi_blockstats: compares images block by block, with standard errors from
 * independent runs (tests of estimators against a reference).
 *
 *   gi_blockstats BLOCK ZMAX REF.exr... -- TEST.exr...
 *
 * Each image is cut into BLOCK x BLOCK pixel blocks; a block's value is its
 * mean over pixels and RGB. Per block, the mean over the REF images and
 * over the TEST images, with their standard errors (sample standard
 * deviation / sqrt(count); 0 for a single image), and
 *   z = (test - ref) / sqrt(se_ref^2 + se_test^2).
 * Prints every block and the largest |z|; exit 0 if every |z| <= ZMAX,
 * 1 if not, 2 on usage or read errors. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_image.h"

typedef struct stats {
    double *sum, *sum2;
    int n;
} stats;

static int add_image(const char *path, int block, int *w, int *h, stats *st)
{
    gi_error err;
    gi_image img;
    if (gi_exr_read(path, &img, &err)) {
        fprintf(stderr, "gi-blockstats: %s\n", err.msg);
        return -1;
    }
    if (*w == 0) {
        *w = img.width;
        *h = img.height;
    }
    if (img.width != *w || img.height != *h || img.width % block || img.height % block) {
        fprintf(stderr, "gi-blockstats: %s: %dx%d does not match or is not a multiple of %d\n",
                path, img.width, img.height, block);
        gi_image_free(&img);
        return -1;
    }
    int bx = img.width / block, by = img.height / block;
    if (!st->sum) {
        st->sum = calloc((size_t)bx * by, sizeof(double));
        st->sum2 = calloc((size_t)bx * by, sizeof(double));
    }
    int ch[3];
    const char *names[3] = {"R", "G", "B"};
    for (int c = 0; c < 3; c++)
        if ((ch[c] = gi_image_channel(&img, names[c])) < 0) {
            fprintf(stderr, "gi-blockstats: %s: no channel %s\n", path, names[c]);
            gi_image_free(&img);
            return -1;
        }
    for (int j = 0; j < by; j++)
        for (int i = 0; i < bx; i++) {
            double s = 0;
            for (int y = j * block; y < (j + 1) * block; y++)
                for (int x = i * block; x < (i + 1) * block; x++) {
                    const float *p = gi_image_at(&img, x, y);
                    s += p[ch[0]] + p[ch[1]] + p[ch[2]];
                }
            s /= 3.0 * block * block;
            st->sum[j * bx + i] += s;
            st->sum2[j * bx + i] += s * s;
        }
    st->n++;
    gi_image_free(&img);
    return 0;
}

static void mean_se(const stats *st, int k, double *mean, double *se)
{
    *mean = st->sum[k] / st->n;
    double var = st->n > 1 ? (st->sum2[k] - st->n * *mean * *mean) / (st->n - 1) : 0.0;
    *se = st->n > 1 && var > 0 ? sqrt(var / st->n) : 0.0;
}

int main(int argc, char **argv)
{
    if (argc < 6) {
        fprintf(stderr, "usage: gi-blockstats BLOCK ZMAX REF.exr... -- TEST.exr...\n");
        return 2;
    }
    int block = atoi(argv[1]);
    double zmax = atof(argv[2]);
    if (block < 1 || !(zmax > 0)) {
        fprintf(stderr, "gi-blockstats: bad BLOCK or ZMAX\n");
        return 2;
    }
    stats ref = {0}, test = {0};
    int w = 0, h = 0, i = 3;
    for (; i < argc && strcmp(argv[i], "--") != 0; i++)
        if (add_image(argv[i], block, &w, &h, &ref))
            return 2;
    for (i++; i < argc; i++)
        if (add_image(argv[i], block, &w, &h, &test))
            return 2;
    if (ref.n == 0 || test.n == 0) {
        fprintf(stderr, "gi-blockstats: need reference and test images\n");
        return 2;
    }
    int bx = w / block, by = h / block, bad = 0;
    double worst = 0, chi2 = 0;
    for (int k = 0; k < bx * by; k++) {
        double mr, sr, mt, st;
        mean_se(&ref, k, &mr, &sr);
        mean_se(&test, k, &mt, &st);
        double se = sqrt(sr * sr + st * st);
        double z = se > 0 ? (mt - mr) / se : (mt == mr ? 0.0 : INFINITY);
        printf("block (%d,%d): reference %.6g +- %.2g, test %.6g +- %.2g, z %+.2f\n", k % bx,
               k / bx, mr, sr, mt, st, z);
        chi2 += z * z;
        if (fabs(z) > worst)
            worst = fabs(z);
        bad += !(fabs(z) <= zmax);
    }
    printf("%d blocks, %d reference and %d test images: largest |z| %.2f, chi2 %.1f, %d beyond %g\n",
           bx * by, ref.n, test.n, worst, chi2, bad, zmax);
    free(ref.sum);
    free(ref.sum2);
    free(test.sum);
    free(test.sum2);
    return bad ? 1 : 0;
}
