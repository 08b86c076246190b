# The workers' standing outlives a gi-farmd restart (docs/farm.md,
# "Blocklisting"): a bad host blocklisted for the tasks of two jobs that a
# healthy one ran, and that healthy host's exclusion from a broken job, are
# still there after gi-farmd stops (SIGTERM) and starts again, with their
# counts, reasons and times, and after it is killed outright (-9) a second
# later too; the broken job still waits for a worker.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
LOG="$TMP/farmd.log"
cornell_job "$TMP/broken.json" 8 32 32 32
cornell_job "$TMP/good.json" 9 32 32 8
BROKEN=$(fault_runs 10 11 12 13 14 15)
OPTS="--heartbeat 0.2 --lease 5 --dead 10 --blocklist-failures 2 --blocklist-seconds 600 \
--max-attempts 20"
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$LOG" -- $OPTS
PORTS="--listen-workers $WADDR --listen-api $API"
start_worker "$TMP/bad.log" env "GI_FAULT_CRASH_TASK=*" -- --connect "$WADDR" --procs 1 \
    --queue 0 --cache "$TMP/c-bad" --name bad
start_worker "$TMP/healthy.log" env "GI_FAULT_CRASH_TASK=$BROKEN" -- --connect "$WADDR" \
    --procs 1 --queue 0 --cache "$TMP/c-healthy" --name healthy
wait_workers 2
c=$("$GI" submit "$TMP/good.json" 2>/dev/null) || fail "submit C"
d=$("$GI" submit "$TMP/good.json" 2>/dev/null) || fail "submit D"
a=$("$GI" submit "$TMP/broken.json" 2>/dev/null) || fail "submit A"
wait_state "$c" done 60
wait_state "$d" done 60
wait_log "$LOG" "worker bad blocklisted for 600 s after [0-9]* task failures of its own"

# worker_field NAME KEY: a number of the worker's view.
worker_field() {
    api /api/v1/workers | tr '{' '\n' | grep "\"name\":\"$1\"" | grep -o "\"$2\":[0-9.]*" |
        cut -d: -f2
}
# excluded_healthy: A's view lists healthy excluded now.
excluded_healthy() {
    api "/api/v1/jobs/$a" | grep -q '"excluded_workers":\[{"worker":"healthy","excluded":true'
}
n=0
until excluded_healthy; do
    n=$((n + 1))
    [ $n -lt 300 ] || { api "/api/v1/jobs/$a"; fail "healthy was not excluded from A"; }
    sleep 0.05
done
own=$(worker_field bad own_failures)
failures_a=$(api "/api/v1/jobs/$a" | grep -o '"times":[0-9]*' | head -n 1)
[ "$own" -ge 2 ] || fail "bad has $own failures of its own"
sleep 1.2 # every change written (once a second at most)

# check WHEN: the standing as it was, after a restart.
check() {
    n=0
    until "$GI" workers 2>/dev/null | grep -q "^bad .*blocklisted" &&
        "$GI" workers | grep -q "^healthy .* active "; do
        n=$((n + 1))
        [ $n -lt 100 ] || { "$GI" workers; fail "$1: bad is not blocklisted, or healthy not back"; }
        sleep 0.1
    done
    "$GI" workers >"$TMP/workers.txt"
    grep -A1 "^bad .*blocklisted" "$TMP/workers.txt" |
        grep -q "^    for 5[0-9][0-9] s more; last: bad: pool child" ||
        { cat "$TMP/workers.txt"; fail "$1: gi workers: not blocklisted as before, or why"; }
    [ "$(worker_field bad own_failures)" = "$own" ] ||
        fail "$1: bad's own failures: $(worker_field bad own_failures), not $own"
    [ "$(worker_field bad consecutive_failures)" -ge 2 ] || fail "$1: bad's streak is gone"
    excluded_healthy || { api "/api/v1/jobs/$a"; fail "$1: A's exclusion of healthy is gone"; }
    api "/api/v1/jobs/$a" | grep -q "$failures_a" || fail "$1: A's exclusion count changed"
    [ "$(jstate "$a")" = running ] || fail "$1: A is $(jstate "$a")"
    api "/api/v1/jobs/$a" | grep -q '"waiting_for_workers":true' ||
        { api "/api/v1/jobs/$a"; fail "$1: A does not wait for a worker"; }
    "$GI" status "$a" |
        grep -q "^  worker healthy excluded from this job until .* ([0-9]* s more)" ||
        { "$GI" status "$a"; fail "$1: gi status does not show the exclusion"; }
}

stop_farmd "$LOG"
[ -s "$TMP/state/standing" ] || fail "no standing file"
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$LOG" -- $OPTS $PORTS
grep -q "the workers' standing restored: 2 hosts, [1-9][0-9]* exclusions" "$LOG" ||
    { tail -n 20 "$LOG"; fail "no line on the standing restored"; }
check "after SIGTERM"
sleep 1.2
kill -9 "$FARMD_PID"
wait "$FARMD_PID" 2>/dev/null || true
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$LOG" -- $OPTS $PORTS
check "after kill -9"

# A damaged file is said and passed over: the farm starts afresh.
stop_farmd "$LOG"
printf 'GIST' >"$TMP/state/standing"
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$LOG" -- $OPTS $PORTS
wait_log "$LOG" "warning: the workers' standing was not restored: .*standing: not a standing file"
wait_workers 2
"$GI" workers | grep -q "^bad .* active " || { "$GI" workers; fail "bad is still blocklisted"; }
stop_farmd "$LOG"
echo ok
