#!/bin/sh
# detp_anim_image: what a user waits for per frame of a detp animation with
# images: the 2.5% sphere of bench/detp_anim.sh moving 1% of the box a
# frame, rendered at WIDTH x HEIGHT (4 samples a pixel) with EXR and PNG
# outputs by `gi render` (WORKERS pool processes, default: one per core).
# Prints the whole render's wall time and, from the frames' reports
# (bench/anim_frames image), frame 0's and the mean over frames 1.. of the
# bake's wall time, the tiles' worker seconds and the image phase's wall
# time; then bench/image_write on the last frame's EXR (the coordinator's
# output writing, which the reports do not time). Also the peak RSS of
# gi render's parent (the coordinator), polled.
#   bench/detp_anim_image.sh BUILD_DIR [FRAMES] [WIDTH] [HEIGHT] [WORKERS] [OUT]
set -eu
BIN=${1:-build/release}
FRAMES=${2:-24}
WIDTH=${3:-1920}
HEIGHT=${4:-1080}
WORKERS=${5:-0}
SRC=$(cd "$(dirname "$0")/.." && pwd)
OUT=${6:-$SRC/bench/out/anim-image}
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
last=$((FRAMES - 1))
"$BIN/scenes/gi_scenegen" cornell-mobile "$SRC/scenes/cornell-box/scene.json" \
    "$OUT/scene.json" --radius 0.025 >/dev/null
cat >"$OUT/job.json" <<JOB
{"scene": "$OUT/scene.json", "method": "detp", "seed": 1,
 "image": {"width": $WIDTH, "height": $HEIGHT},
 "detp": {"photons": 1000000, "batch": 250000, "subdivide": 20, "radius": "auto",
          "estimator": "embree",
          "animation": {"object": "mobile", "frames": $FRAMES,
            "keyframes": [{"frame": 0, "translate": [0, 0, 0]},
                          {"frame": $last, "translate": [$(awk "BEGIN { print 5.56 * $last }"), 0, 0]}]}},
 "outputs": {"json": "r.json", "exr": "f.exr", "png": "f.png"}}
JOB
rm -f "$OUT"/r.*.json "$OUT"/f.*.exr "$OUT"/f.*.png
workers=
[ "$WORKERS" -gt 0 ] && workers="--workers $WORKERS"
t0=$(date +%s.%N)
# shellcheck disable=SC2086
"$BIN/gi" render "$OUT/job.json" $workers --out "$OUT" --progress none >"$OUT/log" 2>&1 &
pid=$!
hwm=0 # the coordinator's (gi render's parent's) peak RSS, polled
while kill -0 "$pid" 2>/dev/null; do
    h=$(awk '/^VmHWM/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
    [ -n "$h" ] && hwm=$h
    sleep 0.1
done
wait "$pid" || { cat "$OUT/log"; exit 1; }
t1=$(date +%s.%N)
awk "BEGIN { printf \"%d frames at ${WIDTH}x${HEIGHT}, 4 spp, EXR + PNG: %.2f s in all; gi render's parent peaked at %.0f MB\\n\", $FRAMES, $t1 - $t0, $hwm / 1024 }"
"$BIN/bench/anim_frames" image "$FRAMES" "$OUT/r"
"$BIN/bench/image_write" "$(printf '%s/f.%04d.exr' "$OUT" $last)" 9
