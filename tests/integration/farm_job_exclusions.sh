# Bad workers per job (docs/farm.md, "Fault tolerance", "Exclusions"):
# job A, whose tasks 10 and up crash on every host and attempt, gets both
# workers excluded from it (its view, gi status, the log, the metric), and
# waits for them, saying so; no worker is blocklisted, so job B (tasks 0-3)
# is done at once on those very workers; A then fails with its task's error
# after --max-attempts runs.
# A bad host, blocklisted for the tasks of several jobs that other hosts
# run, is farm_host_blame.sh's.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
LOG="$TMP/farmd.log"
# A: 4 tiles x 4 passes = 16 tasks; B: 4 tasks (0-3).
cornell_job "$TMP/a.json" 8 32 32 32
cornell_job "$TMP/b.json" 9 32 32 8
start_farmd "$TMP/state" "$LOG" -- --heartbeat 0.2 --lease 5 --dead 10 --blocklist-failures 2 \
    --blocklist-seconds 6 --max-attempts 4
CRASH="GI_FAULT_CRASH_TASK=$(fault_runs 10 11 12 13 14 15)"
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
echo ok
