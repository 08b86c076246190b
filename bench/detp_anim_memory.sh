#!/bin/sh
# detp_anim_memory: peak memory and disk of a detp animation (issue 7: 100
# million photon paths on the Cornell box with a moving sphere on one worker
# host under 1 GiB, the batches on disk). Runs `gi render --workers 2` on
# scene-mobile.json (sphere of radius 10% of the box) for FRAMES frames, the
# sphere moving 1% of the box's width per frame, "json" output only. Every
# 0.5 s it reads VmHWM (the kernel's own peak resident set, so nothing is
# missed between samples) of the coordinator and each pool child, the sum of
# their current VmRSS, and the disk use (du) of the batch directory
# (gi render is given TMPDIR=$TMPDIR/detp-anim-memory.XXXXXX, so only its own
# batch directory is measured); prints the peaks, the per-frame bake wall times
# (wall_bake of each frame's report) and the whole run's wall time.
#   bench/detp_anim_memory.sh BUILD_DIR [PHOTONS] [FRAMES] [BATCH]
# TMPDIR must name a file system with room: about 70 bytes per segment with
# the per-frame deltas here (see BENCHMARKS.md); the script prints `df` first.
set -eu
BIN=${1:-build/release}
PHOTONS=${2:-100000000}
FRAMES=${3:-3}
BATCH=${4:-250000}
SRC=$(cd "$(dirname "$0")/.." && pwd)
: "${TMPDIR:=/var/tmp}"
export TMPDIR
TMP=$(mktemp -d "$TMPDIR/detp-anim-memory.XXXXXX")
trap 'rm -rf "$TMP"' EXIT
df -h "$TMPDIR" | tail -n 1
last=$((FRAMES - 1))
cat >"$TMP/job.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene-mobile.json", "method": "detp", "seed": 1,
 "image": {"width": 64, "height": 64},
 "detp": {"photons": $PHOTONS, "batch": $BATCH, "subdivide": 20, "radius": "auto",
          "estimator": "embree",
          "animation": {"object": "mobile", "frames": $FRAMES,
            "keyframes": [{"frame": 0, "translate": [0, 0, 0]},
                          {"frame": $last, "translate": [$(awk "BEGIN { print 5.56 * $last }"), 0, 0]}]}},
 "outputs": {"json": "report.json"}}
JOB
kb() { awk -v k="$2:" '$1 == k { print $2 }' "/proc/$1/status" 2>/dev/null || true; }
TMPDIR=$TMP /usr/bin/time -v "$BIN/gi" render "$TMP/job.json" --workers 2 --out "$TMP/out" \
    --progress none >"$TMP/log" 2>"$TMP/time" &
tpid=$!
peak_sum=0
peak_disk=0
: >"$TMP/hwm"
while kill -0 $tpid 2>/dev/null; do
    gi=$(pgrep -P $tpid | head -n 1 || true)
    if [ -n "$gi" ]; then
        sum=0
        for p in $gi $(pgrep -P "$gi" || true); do
            r=$(kb "$p" VmRSS)
            h=$(kb "$p" VmHWM)
            [ -n "$r" ] && sum=$((sum + r))
            [ -n "$h" ] && echo "$p $h" >>"$TMP/hwm"
        done
        [ "$sum" -gt "$peak_sum" ] && peak_sum=$sum
        d=$(du -sk "$TMP"/gi-render-* 2>/dev/null | awk '{ s += $1 } END { print s + 0 }')
        [ "$d" -gt "$peak_disk" ] && peak_disk=$d
    fi
    sleep 0.5
done
wait $tpid || { cat "$TMP/log" "$TMP/time"; exit 1; }
echo "photons $PHOTONS, batch $BATCH, frames $FRAMES, 2 pool workers"
awk -v gi="$gi" '{ if ($2 > m[$1]) m[$1] = $2 }
    END { for (p in m) printf "  pid %s%s: peak RSS (VmHWM) %d MiB\n", p,
          p == gi ? " (coordinator)" : "", m[p] / 1024 }' "$TMP/hwm" | sort
echo "  peak RSS sum of all processes (0.5 s samples): $((peak_sum / 1024)) MiB"
echo "  largest process (time -v, max over the waited-for tree): $(($(sed -n 's/.*Maximum resident set size (kbytes): //p' "$TMP/time") / 1024)) MiB"
echo "  peak disk use of the batch directory: $((peak_disk / 1024)) MiB"
echo "  wall: $(sed -n 's/.*Elapsed (wall clock) time.*: //p' "$TMP/time")"
f=0
while [ $f -lt "$FRAMES" ]; do
    r=$TMP/out/report.$(printf %04d $f).json
    seg=$(sed -n 's/^[[:space:]]*"segments":[[:space:]]*\([0-9]*\),*$/\1/p' "$r" | head -n 1)
    wall=$(sed -n 's/^[[:space:]]*"wall_bake":[[:space:]]*\([0-9.e+-]*\),*$/\1/p' "$r")
    ret=$(sed -n 's/^[[:space:]]*"paths_retraced":[[:space:]]*\([0-9]*\),*$/\1/p' "$r")
    echo "  frame $f: segments $seg, paths retraced $ret, wall_bake $wall s"
    f=$((f + 1))
done
