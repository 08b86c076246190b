#!/bin/sh
# detp_memory: peak memory of a detp bake as photons grow (issue 3: 50
# million photons on the Cornell box under 1 GiB). Runs `gi render` with
# 2 pool workers and samples /proc every 0.1 s: the peak of the SUM of the
# resident sets of the coordinator and its children (what the machine must
# hold at once), and the peak of each process alone; /usr/bin/time -v's
# maximum resident set of the coordinator is printed too.
#   bench/detp_memory.sh BUILD_DIR [PHOTONS...]
set -eu
BIN=${1:-build/release}
shift || true
SRC=$(cd "$(dirname "$0")/.." && pwd)
TMP=$(mktemp -d "${TMPDIR:-/tmp}/detp-memory.XXXXXX")
trap 'rm -rf "$TMP"' EXIT
[ $# -gt 0 ] || set -- 5000000 50000000
rss_kb() { awk '/^VmRSS:/ { print $2 }' "/proc/$1/status" 2>/dev/null || echo 0; }
for photons in "$@"; do
    cat >"$TMP/job.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "detp", "seed": 1,
 "image": {"width": 256, "height": 256},
 "detp": {"photons": $photons, "batch": 250000, "subdivide": 12, "estimator": "embree"},
 "outputs": {"png": "img.png", "bin": "v.bin", "json": "report.json"}}
JOB
    /usr/bin/time -v "$BIN/gi" render "$TMP/job.json" --workers 2 --out "$TMP/out" \
        --progress none >"$TMP/log" 2>"$TMP/time" &
    tpid=$!
    peak_sum=0
    peak_one=0
    while kill -0 $tpid 2>/dev/null; do
        gi=$(pgrep -P $tpid | head -n 1 || true)
        if [ -n "$gi" ]; then
            sum=$(rss_kb "$gi")
            [ "$sum" -gt "$peak_one" ] && peak_one=$sum
            for kid in $(pgrep -P "$gi" || true); do
                k=$(rss_kb "$kid")
                sum=$((sum + k))
                [ "$k" -gt "$peak_one" ] && peak_one=$k
            done
            [ "$sum" -gt "$peak_sum" ] && peak_sum=$sum
        fi
        sleep 0.1
    done
    wait $tpid || { cat "$TMP/log" "$TMP/time"; exit 1; }
    wall=$(sed -n 's/.*Elapsed (wall clock) time.*: //p' "$TMP/time")
    coord=$(sed -n 's/.*Maximum resident set size (kbytes): //p' "$TMP/time")
    segs=$(sed -n 's/^[[:space:]]*"segments":[[:space:]]*\([0-9]*\),*$/\1/p' "$TMP/out/report.json")
    echo "photons $photons segments $segs wall $wall: peak RSS sum $((peak_sum / 1024)) MiB," \
        "largest process $((peak_one / 1024)) MiB, coordinator (time -v) $((coord / 1024)) MiB"
done
