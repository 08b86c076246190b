#!/bin/sh
# Does a still's end stop the coordinator? gi-farmd, WORKERS gi-worker
# processes (--procs 1 each) on loopback; a job of many small pt tasks runs
# while a SIZE x SIZE pt still (1 spp: quick to render, its outputs a 4 Mpx
# EXR + PNG at 2048) finishes next to it. A sampler asks GET /metrics every
# few ms meanwhile; reported: the longest time between two rises of
# gi_farm_task_results_total (results merged) and the longest answer of
# the API, from the still's submission to its end (both are the loop's
# stalls: the loop also answers the API), the still's finish_seconds, and
# gi_farm_loop_stall_max_seconds where gi-farmd has it (since 2026-11-27).
#   bench/farm_stall.sh BUILD_DIR [WORKERS] [SIZE]
set -eu
BIN=$(cd "${1:?BUILD_DIR}" && pwd)
WORKERS=${2:-2}
SIZE=${3:-2048}
SRC=$(cd "$(dirname "$0")/.." && pwd)
. "$SRC/bench/farm_env.sh"
k=1
while [ "$k" -le "$WORKERS" ]; do
    "$BIN/gi-worker" --connect "$WADDR" --procs 1 --name "w$k" --cache "$T/cache$k" \
        >"$T/worker$k.log" 2>&1 &
    PIDS="$PIDS $!"
    k=$((k + 1))
done
AUTH="Authorization: Bearer $(cat "$T/token")"
metrics() { curl -s -H "$AUTH" "$GI_FARM/metrics"; }
metric() { metrics | awk -v m="$1" '$1 == m {print $2}'; }
while [ "$(metric 'gi_farm_workers{state="active"}')" != "$WORKERS" ]; do sleep 0.1; done
job() { # FILE NAME SIZE SPP TILE OUTPUTS
    cat >"$1" <<JOB
{"name": "$2", "scene": "$SRC/scenes/cornell-box/scene.json", "method": "pt", "seed": 1,
 "image": {"width": $3, "height": $3}, "pt": {"spp": $4, "tile": $5, "pass_spp": 1},
 "outputs": $6}
JOB
}
# Small tasks: 16 x 16 tiles of 128 x 128 pixels, 1 spp a pass: it outlasts the still.
job "$T/many.json" stall-many 128 4000 16 '{"exr": "many.exr"}'
job "$T/still.json" stall-still "$SIZE" 1 64 '{"exr": "still.exr", "png": "still.png"}'
many=$("$BIN/gi" submit "$T/many.json" 2>/dev/null)
r=0
while [ "$r" = "" ] || [ "$r" -lt 200 ]; do r=$(metric gi_farm_task_results_total); sleep 0.1; done
# The sampler: "time results api_seconds" lines until $T/stop appears.
(
    while [ ! -e "$T/stop" ]; do
        t0=$(date +%s.%N)
        n=$(curl -s -H "$AUTH" -w ' curl_time %{time_total}\n' "$GI_FARM/metrics" |
            awk '$1 == "gi_farm_task_results_total" {n = $2} $1 == "curl_time" {c = $2}
                 END {print n, c}')
        echo "$t0 $n"
    done
) >"$T/samples" &
SAMPLER=$!
PIDS="$PIDS $SAMPLER"
sleep 1
t0=$(date +%s.%N)
"$BIN/gi" submit "$T/still.json" --wait --out "$T/out" --progress none >"$T/still.log" 2>&1 ||
    { cat "$T/still.log"; exit 1; }
t1=$(date +%s.%N)
sleep 1
touch "$T/stop"
wait "$SAMPLER" 2>/dev/null || true
state=$(curl -s -H "$AUTH" "$GI_FARM/api/v1/jobs/$many" | sed 's/.*"state":"\([a-z]*\)".*/\1/')
still=$(curl -s -H "$AUTH" "$GI_FARM/api/v1/jobs" | sed 's/.*"id":\([0-9]*\),"name":"stall-still".*/\1/')
fin=$(curl -s -H "$AUTH" "$GI_FARM/api/v1/jobs/$still" |
    sed 's/.*"finish_seconds":\([0-9.e+-]*\).*/\1/')
stall=$(metric gi_farm_loop_stall_max_seconds)
[ "$state" = running ] || echo "warning: the small tasks' job is $state, not running: rerun"
awk -v t0="$t0" -v t1="$t1" -v fin="$fin" -v stall="${stall:-n/a}" -v size="$SIZE" '
    $1 >= t0 && $1 <= t1 + 1 {
        if (last_n != "" && $2 > last_n) { gap = $1 - last_t; if (gap > worst) worst = gap }
        if (last_n == "" || $2 > last_n) { last_n = $2; last_t = $1 }
        if ($3 > api) api = $3; samples++
    }
    END {printf "still %dx%d: %.1f s; finish %.3f s; longest gap between merges %.3f s; " \
                "longest API answer %.3f s (%d samples); loop_stall_max %s\n",
                size, size, t1 - t0, fin, worst, api, samples, stall}' "$T/samples"
