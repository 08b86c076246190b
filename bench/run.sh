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
echo "== pt_vs_embree on a heavier scene (Cornell box + 163,840 sphere triangles)"
"$BIN/bench/pt_vs_embree" bench/scenes/cornell-spheres.json 256 8 9
