#!/bin/sh
# anim_vs_still: what an animation (pt, quadrature, or a detp or radiosity
# camera path) costs against its stills. Renders JOB (an animation whose frames all
# move, e.g. scenes/cornell-box/pt-animation.json) and the same job without
# its animation block (one still, the mobile as loaded), ROUNDS times each,
# alternated, with `gi render --workers WORKERS`; prints the medians: the
# animation's wall time per frame and the still's (a frame costs what a
# still does if frames add nothing: each frame's tail, its tasks' last
# wave, and its output writes are the extra). Then how many pixels are the
# same bits in consecutive frames (pt draws the same random numbers each
# frame: what the mobile does not touch is unchanged).
#   bench/anim_vs_still.sh BUILD_DIR JOB [ROUNDS] [WORKERS]
set -eu
BIN=${1:-build/release}
JOB=$2
ROUNDS=${3:-3}
WORKERS=${4:-2}
OUT=$(mktemp -d "${TMPDIR:-/tmp}/gi-anim-still.XXXXXX")
trap 'rm -rf "$OUT"' EXIT
frames=$(python3 - "$JOB" "$OUT/still.json" <<'PY'
import json, os, sys
j = json.load(open(sys.argv[1]))
j["scene"] = os.path.join(os.path.dirname(os.path.abspath(sys.argv[1])), j["scene"])
print(j[j["method"]].pop("animation")["frames"])
j["name"] = "still"
json.dump(j, open(sys.argv[2], "w"))
PY
)
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
    printf "%d frames, %d workers: animation %.3f s (%.3f s a frame); ", f, w, a, a / f
    printf "still %.3f s; frame / still %.3f\n", s, a / f / s }'
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
