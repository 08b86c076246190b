#!/bin/sh
# The coordinator's own cost under many workers: gi-farmd and WORKERS
# gi-worker processes (--procs 1 each, their own --name and cache) on
# loopback, the jobs submitted one after another with `gi submit --wait`.
# For each job: tasks (results merged), wall time, gi-farmd's CPU seconds
# (user + system from /proc/PID/stat) and per task, bytes on the worker
# port per task (both directions, from `ss -ti`: what reached the socket),
# result bytes per task, gi-farmd's peak RSS (VmHWM) so far, and the CPU
# seconds of the workers (gi-worker and its pool children): their ratio to
# gi-farmd's is how many busy worker cores one coordinator core feeds. On a
# machine with fewer cores than workers the workers time-share them: the
# wall time says nothing about speedup, the coordinator's CPU does.
#   bench/farm_scale.sh BUILD_DIR WORKERS JOB.json [JOB.json...]
# COPIES=K submits each job K times at once (a queue of K jobs), then waits
# for them all; an argument K*JOB.json does so for that job alone (at most a
# few hundred at once: each is a `gi submit --wait`). PERF=FILE records
# gi-farmd with perf (call graphs) for the whole run. FARMD_ARGS adds
# options to gi-farmd. IDLE=S first measures gi-farmd's CPU for S seconds
# with its workers connected and no job.
set -eu
BIN=$(cd "${1:?BUILD_DIR}" && pwd)
WORKERS=${2:?WORKERS}
shift 2
COPIES=${COPIES:-1}
. "$(dirname "$0")/farm_env.sh"
WPORT=${WADDR##*:}
k=1
while [ "$k" -le "$WORKERS" ]; do
    "$BIN/gi-worker" --connect "$WADDR" --procs 1 --name "w$k" --cache "$T/cache$k" \
        >"$T/worker$k.log" 2>&1 &
    PIDS="$PIDS $!"
    echo $! >>"$T/wpids"
    k=$((k + 1))
done
metric() {
    curl -s -H "Authorization: Bearer $(cat "$T/token")" "$GI_FARM/metrics" |
        awk -v m="$1" '$1 == m {print $2}'
}
while [ "$(metric 'gi_farm_workers{state="active"}')" != "$WORKERS" ]; do sleep 0.1; done
if [ -n "${PERF:-}" ]; then
    perf record -g -o "$PERF" -p "$FARMD_PID" >/dev/null 2>&1 &
    PERF_PID=$!
    sleep 0.5
fi
cpu() { awk '{print ($14 + $15) / 100}' "/proc/$FARMD_PID/stat"; }
# CPU seconds of the gi-worker processes and their pool children.
wcpu() {
    cat /proc/[0-9]*/stat 2>/dev/null | awk -v list="$T/wpids" '
        BEGIN {while ((getline p <list) > 0) w[p] = 1}
        ($1 in w) || ($4 in w) {s += $14 + $15} END {print s / 100}'
}
hwm() { awk '$1 == "VmHWM:" {print $2 / 1024}' "/proc/$FARMD_PID/status"; }
# Bytes through the worker port's sockets, as seen by gi-farmd (received + acked).
net() {
    ss -tinH state established "( sport = :$WPORT )" |
        awk '{for (i = 1; i <= NF; i++) if ($i ~ /^bytes_(acked|received):/) {
                  split($i, kv, ":"); s[kv[1]] += kv[2] }}
             END {printf "%.0f %.0f\n", s["bytes_received"], s["bytes_acked"]}'
}
now() { date +%s.%N; }
printf '%-24s %4s %7s %7s %6s %6s %8s %7s %7s %8s %6s %7s\n' job wrks tasks wall_s cpu_s \
    cpu_us/t in_B/t out_B/t result_B/t hwm_MB wcpu_s w/cpu
if [ -n "${IDLE:-}" ]; then
    # The coordinator with its workers connected and nothing to do, IDLE seconds.
    c0=$(cpu)
    sleep "$IDLE"
    c1=$(cpu)
    awk -v w="$WORKERS" -v c0="$c0" -v c1="$c1" -v s="$IDLE" \
        'BEGIN {printf "idle, %d workers: %.3f s of CPU a second\n", w, (c1 - c0) / s}'
fi
for ARG in "$@"; do
    case $ARG in
    *'*'*) K=${ARG%%'*'*} JOB=${ARG#*'*'} ;;
    *) K=$COPIES JOB=$ARG ;;
    esac
    r0=$(metric gi_farm_task_results_total)
    b0=$(metric gi_farm_result_bytes_total)
    c0=$(cpu) w0=$(wcpu)
    set -- $(net)
    i0=$1 o0=$2
    t0=$(now)
    n=1 SUBMITS=""
    while [ "$n" -le "$K" ]; do
        "$BIN/gi" submit "$JOB" --wait --out "$T/out-$n" --progress none >"$T/submit-$n.log" 2>&1 &
        SUBMITS="$SUBMITS $!"
        n=$((n + 1))
    done
    wait_ok=0
    for p in $SUBMITS; do wait "$p" || wait_ok=$?; done
    [ "$wait_ok" -eq 0 ] || { echo "a job failed:"; cat "$T"/submit-*.log; exit 1; }
    t1=$(now)
    c1=$(cpu) w1=$(wcpu)
    set -- $(net)
    i1=$1 o1=$2
    r1=$(metric gi_farm_task_results_total)
    b1=$(metric gi_farm_result_bytes_total)
    awk -v job="$(basename "$JOB" .json)x$K" -v w="$WORKERS" -v r0="$r0" -v r1="$r1" \
        -v t0="$t0" -v t1="$t1" -v c0="$c0" -v c1="$c1" -v i0="$i0" -v i1="$i1" \
        -v o0="$o0" -v o1="$o1" -v b0="$b0" -v b1="$b1" -v h="$(hwm)" -v w0="$w0" -v w1="$w1" '
        BEGIN {
        n = r1 - r0; if (n < 1) n = 1
        c = c1 - c0; if (c <= 0) c = 0.01
        printf "%-24s %4d %7d %7.2f %6.2f %6.0f %8.0f %7.0f %7.0f %8.1f %6.1f %7.0f\n", job, w,
            r1 - r0, t1 - t0, c1 - c0, 1e6 * (c1 - c0) / n, (i1 - i0) / n, (o1 - o0) / n,
            (b1 - b0) / n, h, w1 - w0, (w1 - w0) / c}'
done
if [ -n "${PERF:-}" ]; then
    kill -INT "$PERF_PID"
    wait "$PERF_PID" 2>/dev/null || true
fi
