# Bad workers per job (docs/farm.md, "Fault tolerance", "Exclusions"):
# 1. Job A, whose tasks 10 and up crash on every host and attempt, gets both
#    workers excluded from it (its view, gi status, the log, the metric),
#    and waits for them, saying so; no worker is blocklisted, so job B
#    (tasks 0-3) is done at once on those very workers; A then fails with
#    its task's error after --max-attempts runs.
# 2. A worker that fails the tasks of two jobs in a row is blocklisted
#    (gi workers says for how long and why), and a healthy one does both.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
LOG="$TMP/farmd.log"
# A: 4 tiles x 4 passes = 16 tasks; B (also run as C and D): 4 tasks (0-3).
cornell_job "$TMP/a.json" 8 32 32 32
cornell_job "$TMP/b.json" 9 32 32 8

# excluded ID: the workers excluded from the job now, by name, sorted.
excluded() {
    api "/api/v1/jobs/$1" | tr '{' '\n' | sed -n 's/^"worker":"\([^"]*\)","excluded":true,.*/\1/p' |
        sort | tr '\n' ' '
}

# 1. Exclusions from one job.
start_farmd "$TMP/state" "$LOG" -- --heartbeat 0.2 --lease 5 --dead 10 --blocklist-failures 2 \
    --blocklist-seconds 6 --max-attempts 4
# runs IDS...: every attempt (0-7) of those task ids, as the hooks name runs.
runs() {
    for t in "$@"; do for k in 0 1 2 3 4 5 6 7; do printf '%s:%s,' "$t" "$k"; done; done |
        sed 's/,$//'
}
CRASH="GI_FAULT_CRASH_TASK=$(runs 10 11 12 13 14 15)"
for w in w1 w2; do
    start_worker "$TMP/$w.log" env "$CRASH" -- --connect "$WADDR" --procs 1 --cache "$TMP/c-$w" \
        --name "$w"
done
wait_workers 2
a=$("$GI" submit "$TMP/a.json" 2>/dev/null) || fail "submit A"
n=0
until [ "$(excluded "$a")" = "w1 w2 " ]; do
    n=$((n + 1))
    [ $n -lt 300 ] && [ "$(jstate "$a")" = running ] ||
        { api "/api/v1/jobs/$a"; fail "A's view does not list both workers excluded"; }
    sleep 0.05
done
"$GI" status "$a" >"$TMP/status-a.txt"
for w in w1 w2; do
    # Said once (a warning), with the job, the worker and its last error.
    [ "$(grep -c "job $a: worker $w excluded from it" "$LOG")" = 1 ] &&
        grep -q "warning: job $a: worker $w excluded from it for 6 s after [0-9]* of its task \
failures in a row (it still serves other jobs); last: $w: pool child" "$LOG" ||
        fail "the coordinator's log does not say once that $w is excluded from A"
    grep -q "^  worker $w excluded from this job until 20[0-9-]*T[0-9:]*Z ([0-9]* s more); last: \
$w: pool child .* was killed by signal 9" "$TMP/status-a.txt" ||
        { cat "$TMP/status-a.txt"; fail "gi status does not show $w excluded, until when and why"; }
done
api "/api/v1/jobs/$a" | grep -q '"waiting_for_workers":true' ||
    { api "/api/v1/jobs/$a"; fail "A's view does not say it waits for a worker"; }
grep -q "^  waiting: no connected worker may take its tasks now" "$TMP/status-a.txt" ||
    { cat "$TMP/status-a.txt"; fail "gi status does not say A waits for a worker"; }
api "/api/v1/jobs/$a" | grep -q "no connected worker may take its tasks now (excluded or \
blocklisted): they wait, 6 s at most" || { api "/api/v1/jobs/$a"; fail "A's log: no wait"; }
api /api/v1/workers | grep -q '"state":"blocklisted"' &&
    { api /api/v1/workers; fail "a worker was blocklisted for one job's failures"; }
[ "$(metric gi_farm_job_exclusions_total)" -ge 2 ] ||
    fail "gi_farm_job_exclusions_total: $(metric gi_farm_job_exclusions_total)"

# B runs on the workers excluded from A, well within their 6 s exclusion.
t0=$(date +%s)
b=$("$GI" submit "$TMP/b.json" 2>/dev/null) || fail "submit B"
wait_state "$b" done 30
secs=$(($(date +%s) - t0))
[ $secs -le 4 ] || fail "B took $secs s: it waited for the workers excluded from A"
api /api/v1/workers | grep -q '"state":"blocklisted"' &&
    { api /api/v1/workers; fail "a worker was blocklisted"; }
[ "$(metric 'gi_farm_workers{state="blocklisted"}')" = 0 ] || fail "blocklisted workers in /metrics"
"$GI" fetch "$b" --out "$TMP/out-b" >/dev/null || fail "fetch B"
cmp "$TMP/b.json.ref/img.exr" "$TMP/out-b/img.exr" || fail "B's image differs"

# A fails with its task's error once a task has run 4 times (the
# exclusions end, and their next failure renews them).
wait_state "$a" failed 60
api "/api/v1/jobs/$a" >"$TMP/a.json.view"
why='"message":"task 1[0-5] failed 4 times; last error: w[12]: pool child .* killed by signal 9'
grep -q "$why" "$TMP/a.json.view" || { cat "$TMP/a.json.view"; fail "A: not its task's error"; }
grep -q '"excluded_workers":\[{"worker":"w[12]"' "$TMP/a.json.view" ||
    { cat "$TMP/a.json.view"; fail "A's view does not list its exclusions once it failed"; }
! grep -q "worker .* blocklisted for" "$LOG" || fail "a worker was blocklisted"
stop_farmd "$LOG"
for w in $WORKER_PIDS; do kill "$w" 2>/dev/null || true; done
for w in $WORKER_PIDS; do wait "$w" 2>/dev/null || true; done
WORKER_PIDS=""

# 2. One worker fails the tasks of two jobs in a row: blocklisted.
LOG2="$TMP/farmd2.log"
start_farmd "$TMP/state2" "$LOG2" -- --heartbeat 0.2 --lease 5 --dead 10 --blocklist-failures 3 \
    --blocklist-seconds 600 --max-attempts 20
start_worker "$TMP/bad.log" env "GI_FAULT_CRASH_TASK=$(runs 0 1 2 3)" -- --connect "$WADDR" \
    --procs 1 --queue 0 --cache "$TMP/c-bad" --name bad
wait_workers 1
c=$("$GI" submit "$TMP/b.json" 2>/dev/null) || fail "submit C"
d=$("$GI" submit "$TMP/b.json" 2>/dev/null) || fail "submit D"
wait_log "$LOG2" "worker bad blocklisted for 600 s after [0-9]* task failures (of more than one job"
grep -q "job $c: task [0-9]* (attempt [0-9]*) failed on bad" "$LOG2" &&
    grep -q "job $d: task [0-9]* (attempt [0-9]*) failed on bad" "$LOG2" ||
    { tail -n 30 "$LOG2"; fail "bad did not fail the tasks of both jobs"; }
"$GI" workers >"$TMP/workers.txt"
grep -A1 "^bad .*blocklisted" "$TMP/workers.txt" |
    grep -q "^    for [0-9]* s more; last: .*pool child" ||
    { cat "$TMP/workers.txt"; fail "gi workers does not show it blocklisted, how long and why"; }
start_worker "$TMP/good.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/c-good" --name good
wait_state "$c" done 60
wait_state "$d" done 60
"$GI" fetch "$d" --out "$TMP/out-d" >/dev/null || fail "fetch D"
cmp "$TMP/b.json.ref/img.exr" "$TMP/out-d/img.exr" || fail "D's image differs"
stop_farmd "$LOG2"
echo ok
