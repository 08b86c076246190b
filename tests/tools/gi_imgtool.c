/* gi-imgtool: numeric checks on EXR outputs, for the integration tests.
 *
 *   stats FILE                      mean / min / max of R, G, B
 *   check-const FILE VALUE REL      every R, G, B value within REL of VALUE
 *   check-mean FILE VALUE REL       mean radiance (RGB average) within REL of VALUE
 *   compare-mean A B REL            means of A and B within REL of each other
 *   rmse A B                        relative RMSE of A against B (RGB)
 *   same-pixels A B                 how many pixels are the same bits in both (RGB)
 *
 * Exit status: 0 pass, 1 check failed, 2 usage or unreadable file. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_image.h"

static int load(const char *path, gi_image *img, int ch[3])
{
    gi_error err;
    if (gi_exr_read(path, img, &err)) {
        fprintf(stderr, "gi-imgtool: %s\n", err.msg);
        return -1;
    }
    const char *names[3] = {"R", "G", "B"};
    for (int c = 0; c < 3; c++) {
        ch[c] = gi_image_channel(img, names[c]);
        if (ch[c] < 0) {
            fprintf(stderr, "gi-imgtool: %s: no channel %s\n", path, names[c]);
            gi_image_free(img);
            return -1;
        }
    }
    return 0;
}

static double image_mean(const gi_image *img, const int ch[3], double mean[3])
{
    size_t n = (size_t)img->width * img->height;
    double all = 0;
    for (int c = 0; c < 3; c++) {
        double s = 0;
        for (size_t i = 0; i < n; i++)
            s += img->pixels[i * img->channels + ch[c]];
        mean[c] = s / (double)n;
        all += mean[c] / 3.0;
    }
    return all;
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: gi-imgtool stats|check-const|check-mean|compare-mean|rmse|"
                        "same-pixels ...\n");
        return 2;
    }
    const char *cmd = argv[1];
    gi_image a, b;
    int ca[3], cb[3];
    if (load(argv[2], &a, ca))
        return 2;
    size_t n = (size_t)a.width * a.height;
    int status = 0;
    if (strcmp(cmd, "stats") == 0) {
        double mean[3];
        double all = image_mean(&a, ca, mean);
        printf("size %dx%d\nmean %.9g %.9g %.9g\navg %.9g\n", a.width, a.height, mean[0],
               mean[1], mean[2], all);
    } else if (strcmp(cmd, "check-const") == 0 && argc == 5) {
        double v = atof(argv[3]), rel = atof(argv[4]), worst = 0;
        size_t wi = 0;
        for (size_t i = 0; i < n; i++)
            for (int c = 0; c < 3; c++) {
                double d = fabs(a.pixels[i * a.channels + ca[c]] - v) / v;
                if (!(d <= worst)) {
                    worst = d;
                    wi = i;
                }
            }
        printf("worst relative deviation %.6f at pixel (%zu, %zu)\n", worst, wi % a.width,
               wi / a.width);
        status = worst <= rel ? 0 : 1;
    } else if (strcmp(cmd, "check-mean") == 0 && argc == 5) {
        double mean[3], v = atof(argv[3]), rel = atof(argv[4]);
        double all = image_mean(&a, ca, mean);
        printf("mean %.9g expected %.9g relative error %.6f\n", all, v, fabs(all - v) / v);
        status = fabs(all - v) <= rel * v ? 0 : 1;
    } else if ((strcmp(cmd, "compare-mean") == 0 && argc == 5) ||
               (strcmp(cmd, "rmse") == 0 && argc == 4) ||
               (strcmp(cmd, "same-pixels") == 0 && argc == 4)) {
        if (load(argv[3], &b, cb)) {
            gi_image_free(&a);
            return 2;
        }
        if (a.width != b.width || a.height != b.height) {
            fprintf(stderr, "gi-imgtool: images differ in size\n");
            status = 2;
        } else if (cmd[0] == 's') {
            size_t same = 0;
            for (size_t i = 0; i < n; i++) {
                int c = 0;
                while (c < 3 && memcmp(&a.pixels[i * a.channels + ca[c]],
                                       &b.pixels[i * b.channels + cb[c]], sizeof *a.pixels) == 0)
                    c++;
                same += c == 3;
            }
            printf("%zu of %zu pixels the same\n", same, n);
        } else if (cmd[0] == 'c') {
            double ma[3], mb[3], rel = atof(argv[4]);
            double x = image_mean(&a, ca, ma), y = image_mean(&b, cb, mb);
            printf("means %.9g %.9g relative difference %.6f\n", x, y, fabs(x - y) / y);
            status = fabs(x - y) <= rel * y ? 0 : 1;
        } else {
            double mb[3], se = 0;
            double y = image_mean(&b, cb, mb);
            for (size_t i = 0; i < n; i++)
                for (int c = 0; c < 3; c++) {
                    double d = a.pixels[i * a.channels + ca[c]] - b.pixels[i * b.channels + cb[c]];
                    se += d * d;
                }
            printf("%.9g\n", sqrt(se / (3.0 * (double)n)) / y);
        }
        gi_image_free(&b);
    } else {
        fprintf(stderr, "gi-imgtool: bad command or arguments\n");
        status = 2;
    }
    gi_image_free(&a);
    return status;
}
