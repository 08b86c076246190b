#!/bin/sh
# resume_anim: what `gi render --resume` costs after an animation was stopped.
# A detp animation of the Cornell box with the 10% mobile sphere
# (gi_scenegen cornell-mobile, as bench/detp_anim.sh), FRAMES frames, a 64x64
# image per frame, is interrupted (SIGINT) once frame STOP's image is
# written, then resumed; prints the seconds of the whole first render's
# frames (an uninterrupted reference run), of the resume, and how many
# batch-frames the resume traced again (the reports' frames_regenerated).
#   bench/resume_anim.sh BUILD_DIR [PHOTONS] [BATCH] [FRAMES] [STOP] [GI] [OUT]
# GI: the gi binary to measure (default BUILD_DIR/gi; an older build's gi
# compares). OUT (default bench/out/resume, gitignored) keeps the runs.
set -eu
BIN=${1:-build/release}
PHOTONS=${2:-4000000}
BATCH=${3:-500000}
FRAMES=${4:-24}
STOP=${5:-16}
GI=${6:-$BIN/gi}
SRC=$(cd "$(dirname "$0")/.." && pwd)
OUT=${7:-$SRC/bench/out/resume}
mkdir -p "$OUT/tmp"
OUT=$(cd "$OUT" && pwd)
export TMPDIR="$OUT/tmp"
last=$((FRAMES - 1))
"$BIN/scenes/gi_scenegen" cornell-mobile "$SRC/scenes/cornell-box/scene.json" \
    "$OUT/scene.json" --radius 0.1 >/dev/null
cat >"$OUT/job.json" <<JOB
{"scene": "$OUT/scene.json", "method": "detp", "seed": 1, "image": {"width": 64, "height": 64},
 "detp": {"photons": $PHOTONS, "batch": $BATCH, "subdivide": 20, "radius": "auto",
          "estimator": "embree",
          "animation": {"object": "mobile", "frames": $FRAMES,
            "keyframes": [{"frame": 0, "translate": [0, 0, 0]},
                          {"frame": $last, "translate": [$(awk "BEGIN { print 5.56 * $last }"), 0, 0]}]}},
 "outputs": {"exr": "img.exr", "json": "r.json"}}
JOB
now() { date +%s.%N; }
frame=$(printf '%04d' "$STOP")

rm -rf "$OUT/ref" "$OUT/run"
t0=$(now)
"$GI" render "$OUT/job.json" --workers 2 --out "$OUT/ref" --progress none >/dev/null 2>&1
t1=$(now)

"$GI" render "$OUT/job.json" --workers 2 --out "$OUT/run" --progress none >"$OUT/stop.log" 2>&1 &
pid=$!
until [ -e "$OUT/run/img.$frame.exr" ]; do
    kill -0 $pid 2>/dev/null || { cat "$OUT/stop.log"; echo "ended before frame $STOP" >&2; exit 1; }
    sleep 0.02
done
kill -INT $pid
wait $pid || true
kept=$(du -sm "$TMPDIR" | cut -f1)
t2=$(now)
"$GI" render "$OUT/job.json" --workers 2 --out "$OUT/run" --progress none --resume \
    >"$OUT/resume.log" 2>&1
t3=$(now)
regen=$(grep -ho '"frames_regenerated":[^,}]*' "$OUT"/run/r.*.json | awk -F: '{s += $2} END {print s}')
for f in "$OUT"/ref/img.*.exr; do
    cmp -s "$f" "$OUT/run/$(basename "$f")" || { echo "$(basename "$f") differs" >&2; exit 1; }
done
awk -v a="$t0" -v b="$t1" -v c="$t2" -v d="$t3" -v r="$regen" -v k="$kept" -v s="$STOP" -v n="$FRAMES" \
    'BEGIN { printf "uninterrupted %.2f s; stopped at frame %d of %d, %d MB of batches kept; resume %.2f s, batch-frames regenerated %d; outputs identical\n", b - a, s, n, k, d - c, r }'
