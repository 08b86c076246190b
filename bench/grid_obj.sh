#!/bin/sh
# Prints an OBJ of an N x N grid of quads in the unit square of y = 0
# (N=700: 25 MB, 980,000 triangles), a large mesh for the benchmarks.
#   sh bench/grid_obj.sh N >grid.obj
set -eu
awk -v n="${1:?N}" 'BEGIN {
    for (i = 0; i <= n; i++) for (j = 0; j <= n; j++) printf "v %.6f 0 %.6f\n", i / n, j / n
    for (i = 0; i < n; i++) for (j = 0; j < n; j++) {
        a = i * (n + 1) + j + 1
        printf "f %d %d %d %d\n", a, a + 1, a + n + 2, a + n + 1
    }
}'
