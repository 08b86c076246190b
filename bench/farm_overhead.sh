#!/bin/sh
# The farm's overhead: the same job through gi-farmd + one gi-worker with 2
# processes on loopback (`gi submit --wait`: upload check, scene check,
# scheduling, TCP, merging, download) against `gi render --workers 2`.
# Runs alternate; medians are reported. Then the coordinator's merge
# throughput (result bytes / time inside merge) from its metrics, for the
# benchmark job and for a job with large results. With JOB.json, that job
# instead (every output but the JSON reports compared), with the CPU seconds the coordinator and
# the worker's relay spent on each farm run, and no merge figures.
#   bench/farm_overhead.sh BUILD_DIR [ROUNDS] [JOB.json]
set -eu
BIN=$(cd "${1:-build/release}" && pwd)
ROUNDS=${2:-5}
JOB=${3:-}
[ -z "$JOB" ] || JOB=$(cd "$(dirname "$JOB")" && pwd)/$(basename "$JOB")
SRC=$(cd "$(dirname "$0")/.." && pwd)
. "$SRC/bench/farm_env.sh"
"$BIN/gi-worker" --connect "$WADDR" \
    --procs 2 --cache "$T/cache" >"$T/worker.log" 2>&1 &
PIDS="$PIDS $!"
RELAY_PID=$!

job() { # FILE W H SPP TILE PASS
    cat >"$1" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "pt", "seed": 1,
 "image": {"width": $2, "height": $3}, "pt": {"spp": $4, "tile": $5, "pass_spp": $6},
 "outputs": {"exr": "img.exr"}}
JOB
}
now() { date +%s.%N; }
metric() {
    curl -s -H "Authorization: Bearer $(cat "$T/token")" "$GI_FARM/metrics" | awk -v m="$1" '$1 == m {print $2}'
}
median() { sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
cpu() { awk '{print ($14 + $15) / 100}' "/proc/$1/stat"; } # user + system seconds

if [ -n "$JOB" ]; then
    echo "job: $JOB"
    "$BIN/gi" submit "$JOB" --wait --out "$T/o" --progress none >/dev/null 2>&1
    i=0
    while [ $i -lt "$ROUNDS" ]; do
        rm -rf "$T/l" "$T/f"
        t0=$(now)
        "$BIN/gi" render "$JOB" --workers 2 --out "$T/l" --progress none >/dev/null
        t1=$(now)
        c0=$(cpu "$FARMD_PID") r0=$(cpu "$RELAY_PID")
        "$BIN/gi" submit "$JOB" --wait --out "$T/f" --progress none >/dev/null 2>&1
        t2=$(now)
        c1=$(cpu "$FARMD_PID") r1=$(cpu "$RELAY_PID")
        for o in "$T"/l/*; do
            case $o in *.json) continue ;; esac # reports hold timings
            cmp -s "$o" "$T/f/$(basename "$o")" || { echo "outputs differ: $(basename "$o")"; exit 1; }
        done
        awk -v a="$t0" -v b="$t1" -v c="$t2" -v c0="$c0" -v c1="$c1" -v r0="$r0" -v r1="$r1" \
            -v n=$((i + 1)) 'BEGIN {printf "round %d: gi render %.2f s, farm %.2f s (coordinator CPU %.2f s, worker relay CPU %.2f s)\n", n, b - a, c - b, c1 - c0, r1 - r0}'
        i=$((i + 1))
    done
    exit 0
fi

# The benchmark job (override with BENCH_JOB="W H SPP TILE PASS_SPP").
set -- ${BENCH_JOB:-320 240 96 32 16}
job "$T/bench.json" "$@"
echo "job: Cornell box, pt, $1x$2, $3 spp, $4-pixel tiles, $5 spp per task ($(( ($1 + $4 - 1) / $4 * (($2 + $4 - 1) / $4) * (($3 + $5 - 1) / $5) )) tasks)"
# Warm-up: page cache, the worker's asset cache and its children's first job.
"$BIN/gi" submit "$T/bench.json" --wait --out "$T/o" --progress none >/dev/null 2>&1
: >"$T/local"
: >"$T/farm"
b0=$(metric gi_farm_merged_bytes_total)
m0=$(metric gi_farm_merge_seconds_total)
i=0
while [ $i -lt "$ROUNDS" ]; do
    t0=$(now)
    "$BIN/gi" render "$T/bench.json" --workers 2 --out "$T/l" --progress none >/dev/null
    t1=$(now)
    "$BIN/gi" submit "$T/bench.json" --wait --out "$T/f" --progress none >/dev/null 2>&1
    t2=$(now)
    cmp -s "$T/l/img.exr" "$T/f/img.exr" || { echo "outputs differ"; exit 1; }
    awk -v a="$t0" -v b="$t1" 'BEGIN {print b - a}' >>"$T/local"
    awk -v a="$t1" -v b="$t2" 'BEGIN {print b - a}' >>"$T/farm"
    printf 'round %d: gi render %.2f s, farm %.2f s\n' $((i + 1)) "$(tail -n 1 "$T/local")" "$(tail -n 1 "$T/farm")"
    i=$((i + 1))
done
l=$(median <"$T/local")
f=$(median <"$T/farm")
awk -v l="$l" -v f="$f" 'BEGIN {printf "median: gi render --workers 2 %.2f s, farm %.2f s, overhead %+.1f%%\n", l, f, 100 * (f - l) / l}'
l=$(sort -g "$T/local" | head -n 1)
f=$(sort -g "$T/farm" | head -n 1)
awk -v l="$l" -v f="$f" 'BEGIN {printf "fastest: gi render --workers 2 %.2f s, farm %.2f s, overhead %+.1f%%\n", l, f, 100 * (f - l) / l}'
b1=$(metric gi_farm_merged_bytes_total)
m1=$(metric gi_farm_merge_seconds_total)
awk -v b0="$b0" -v b1="$b1" -v m0="$m0" -v m1="$m1" -v r="$ROUNDS" 'BEGIN {b = b1 - b0; m = m1 - m0;
    printf "merge: %.1f MB of results per job, %.1f ms merging per job, %.0f MB/s\n", b / r / 1e6, 1000 * m / r, b / m / 1e6}'

# Large results: 1024x1024, 256-pixel tiles, 1 spp per task (2 MiB per result).
job "$T/big.json" 1024 1024 4 256 1
b0=$(metric gi_farm_merged_bytes_total)
m0=$(metric gi_farm_merge_seconds_total)
"$BIN/gi" submit "$T/big.json" --wait --out "$T/b" --progress none >/dev/null 2>&1
b1=$(metric gi_farm_merged_bytes_total)
m1=$(metric gi_farm_merge_seconds_total)
awk -v b0="$b0" -v b1="$b1" -v m0="$m0" -v m1="$m1" 'BEGIN {b = b1 - b0; m = m1 - m0;
    printf "merge, large results (1024x1024, 2 MiB per task): %.0f MB in %.1f ms, %.0f MB/s\n", b / 1e6, 1000 * m, b / m / 1e6}'
