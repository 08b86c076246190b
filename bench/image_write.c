/* image_write: what writing a frame's image outputs costs on the
 * coordinator (an animation writes them every frame while the workers
 * wait). Reads an EXR (e.g. a rendered frame), then writes it ROUNDS times
 * as EXR and as PNG, alternated, into a temporary directory: median
 * seconds and bytes of each (the writes include the fsync and rename).
 *   image_write IMAGE.exr [ROUNDS] */
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bench_util.h"
#include "gi_fs.h"
#include "gi_image.h"

#define MAX_ROUNDS 101

static long file_bytes(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: image_write IMAGE.exr [ROUNDS]\n");
        return 2;
    }
    int rounds = argc > 2 ? atoi(argv[2]) : 9;
    if (rounds < 1 || rounds > MAX_ROUNDS)
        rounds = 9;
    gi_error err;
    gi_image img;
    if (gi_exr_read(argv[1], &img, &err)) {
        fprintf(stderr, "image_write: %s\n", err.msg);
        return 1;
    }
    char dir[] = "/tmp/gi-image-write.XXXXXX";
    if (!mkdtemp(dir)) {
        perror("image_write: mkdtemp");
        return 1;
    }
    char exr[64], png[64];
    snprintf(exr, sizeof exr, "%s/f.exr", dir);
    snprintf(png, sizeof png, "%s/f.png", dir);
    double t_exr[MAX_ROUNDS], t_png[MAX_ROUNDS];
    int rc = 0;
    for (int r = 0; r < rounds && rc == 0; r++) {
        double t0 = gi_bench_now();
        rc = gi_exr_write(exr, &img, &err);
        double t1 = gi_bench_now();
        rc = rc ? rc : gi_png_write(png, &img, 0.0, &err);
        double t2 = gi_bench_now();
        t_exr[r] = t1 - t0;
        t_png[r] = t2 - t1;
    }
    if (rc == 0) {
        printf("%d x %d, %d channels, median of %d\n", img.width, img.height, img.channels,
               rounds);
        printf("exr  %.4f s  %ld bytes\n", gi_bench_median(t_exr, rounds), file_bytes(exr));
        printf("png  %.4f s  %ld bytes\n", gi_bench_median(t_png, rounds), file_bytes(png));
    } else {
        fprintf(stderr, "image_write: %s\n", err.msg);
    }
    unlink(exr);
    unlink(png);
    rmdir(dir);
    gi_image_free(&img);
    return rc ? 1 : 0;
}
