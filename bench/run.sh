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
echo "== farm_overhead: a job through gi-farmd + gi-worker (2 processes, loopback) vs gi render --workers 2"
sh bench/farm_overhead.sh "$BIN" 5
