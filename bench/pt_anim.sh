#!/bin/sh
# pt_anim: what an animation costs the path tracer against its stills.
# Renders scenes/cornell-box/pt-animation.json (24 frames, 256 x 256, 32
# spp; its 24 frames all move) and the same job without its animation block
# (one still), ROUNDS times each, alternated, with `gi render --workers
# WORKERS`; prints the medians: the animation's wall time per frame and the
# still's (a frame costs what a still does if frames add nothing: each
# frame's tail, its tasks' last wave, and its image write are the extra).
# Then how many pixels are the same bits in consecutive frames (the same
# random numbers each frame: what the sphere does not touch is unchanged).
#   bench/pt_anim.sh BUILD_DIR [ROUNDS] [WORKERS]
set -eu
BIN=${1:-build/release}
ROUNDS=${2:-3}
WORKERS=${3:-2}
SRC=$(cd "$(dirname "$0")/.." && pwd)
OUT=$(mktemp -d "${TMPDIR:-/tmp}/gi-pt-anim.XXXXXX")
trap 'rm -rf "$OUT"' EXIT
JOB="$SRC/scenes/cornell-box/pt-animation.json"
python3 - "$JOB" "$OUT/still.json" "$SRC/scenes/cornell-box" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
j["scene"] = sys.argv[3] + "/" + j["scene"]
del j["pt"]["animation"]
j["name"] = "still"
json.dump(j, open(sys.argv[2], "w"))
PY
frames=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['pt']['animation']['frames'])" "$JOB")
timed() { # timed JOB DIR: wall seconds of gi render
    t0=$(date +%s.%N)
    "$BIN/gi" render "$1" --workers "$WORKERS" --out "$2" --progress none >/dev/null
    awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.3f\n", b - a }'
}
: >"$OUT/anim.t"
: >"$OUT/still.t"
for r in $(seq 1 "$ROUNDS"); do
    timed "$JOB" "$OUT/anim" >>"$OUT/anim.t"
    timed "$OUT/still.json" "$OUT/still" >>"$OUT/still.t"
done
median() { sort -n "$1" | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'; }
a=$(median "$OUT/anim.t")
s=$(median "$OUT/still.t")
awk -v a="$a" -v s="$s" -v f="$frames" -v w="$WORKERS" 'BEGIN {
    printf "%d frames, %d workers: animation %.3f s (%.3f s a frame); still %.3f s; frame / still %.3f\n",
        f, w, a, a / f, s, a / f / s }'
total=0
same=0
prev=
for img in "$OUT"/anim/*.exr; do
    if [ -n "$prev" ]; then
        line=$("$BIN/tools/gi_imgtool" same-pixels "$prev" "$img")
        same=$((same + ${line%% of*}))
        rest=${line#* of }
        total=$((total + ${rest%% *}))
    fi
    prev=$img
done
awk -v s="$same" -v t="$total" 'BEGIN {
    printf "consecutive frames: %.1f%% of pixels the same bits\n", 100 * s / t }'
