#!/bin/sh
# make bench: runs every benchmark driver and prints its table. Numbers are
# recorded by hand in bench/BENCHMARKS.md with the command that made them.
#   bench/run.sh BUILD_DIR
set -eu
BIN=${1:-build/release}
SRC=$(cd "$(dirname "$0")/.." && pwd)
cd "$SRC"
echo "== pt_vs_embree: path tracer vs bare Embree on the same rays (one core)"
"$BIN/bench/pt_vs_embree" scenes/cornell-box/scene.json 256 8 9
echo "== quad_genz: adaptive cubature on Genz's test families (evaluations for 1e-3 and 1e-6)"
"$BIN/bench/quad_genz" 6 2e7
echo "== quad_heap: bucketed vs binary vs pairing heap (median of 9 alternating rounds)"
"$BIN/bench/quad_heap" 2000000 9
echo "== quad_vs_pt: quadrature vs path tracer at equal time on the Cornell box (references cached in out/bench)"
"$BIN/bench/quad_vs_pt" scenes/cornell-box/scene.json out/bench 16384 3
