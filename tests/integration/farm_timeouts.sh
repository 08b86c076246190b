# Task time limits on the farm: a task that hangs (GI_FAULT_HANG_TASK: its
# pool child sleeps instead of running it) is stopped when it has run on its
# worker's pool longer than its job's task_timeout (or gi-farmd's
# --task-timeout), however long it waited in the worker's queue before:
# the worker kills the child, the run fails as an attempt, and the retry
# finishes the job with the image of `gi render`; a task that hangs on
# every run fails its job with the timeout after --max-attempts. Timeouts
# are not held against the host (it is never blocklisted for them). The
# hang is the hook's, so the only timing is the limit itself (2 s, far
# above a 32x32 task's run even on a loaded machine). Without the limit
# the jobs would wait forever: `timeout` turns that into a failure.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
cornell_job "$TMP/job.json" 8 32 32 32 8 # 4 tiles x 4 passes: 16 tasks
sed 's/"seed": 8,/"seed": 8, "task_timeout": 2,/' "$TMP/job.json" >"$TMP/limited.json"
grep -q '"task_timeout": 2' "$TMP/limited.json" || fail "the limited job has no task_timeout"

"$FARMD" --state "$TMP/bad" --task-timeout 0.5 >"$TMP/flag.log" 2>&1 && fail "--task-timeout 0.5"
grep -q -- '--task-timeout must be 0 (no limit) or seconds in \[1, 1e+06\]' "$TMP/flag.log" ||
    { cat "$TMP/flag.log"; fail "no clear error for --task-timeout 0.5"; }
"$FARMD" --state "$TMP/bad" --task-timeout -1 >"$TMP/flag.log" 2>&1 && fail "--task-timeout -1"
grep -q -- '--task-timeout: "-1" is not a number of seconds' "$TMP/flag.log" ||
    { cat "$TMP/flag.log"; fail "no clear error for --task-timeout -1"; }
"$FARMD" --help | grep -q -- "--task-timeout S" || fail "--help does not name --task-timeout"

# 1. The job's own limit (2 s) wins over gi-farmd's (1000 s): task 2 hangs
# on its first run only, is stopped after 2 s and retried; the job is done.
LOG="$TMP/farmd.log"
start_farmd "$TMP/state" "$LOG" -- --heartbeat 0.2 --lease 3 --dead 10 --max-attempts 3 \
    --task-timeout 1000 --blocklist-failures 1
start_worker "$TMP/w1.log" env GI_FAULT_HANG_TASK=2:0 -- --connect "$WADDR" --procs 2 \
    --cache "$TMP/c1" --name w1
id=$("$GI" submit "$TMP/limited.json" 2>/dev/null) || fail "submit"
timeout 120 "$GI" wait "$id" --out "$TMP/out" --progress none >"$TMP/wait1.log" 2>&1 ||
    { cat "$TMP/wait1.log"; fail "the job of a task that hung once did not finish"; }
cmp "$TMP/job.json.ref/img.exr" "$TMP/out/img.exr" || fail "image differs after the timeout"
[ "$(jnum "$id" retries)" = 1 ] || { api "/api/v1/jobs/$id"; fail "retries: $(jnum "$id" retries)"; }
[ "$(jnum "$id" timeouts)" = 1 ] || { api "/api/v1/jobs/$id"; fail "timeouts: $(jnum "$id" timeouts)"; }
"$GI" status "$id" | grep -q "1 retries (1 run stopped for the task_timeout)" ||
    { "$GI" status "$id"; fail "gi status does not show the timeout"; }
[ "$(jnum "$id" losses)" = 0 ] || { api "/api/v1/jobs/$id"; fail "a timeout counted as a loss"; }
[ "$(metric gi_farm_task_timeouts_total)" = 1 ] ||
    fail "task_timeouts metric: $(metric gi_farm_task_timeouts_total)"
api "/api/v1/jobs/$id" | grep -q "task 2 (attempt 0) failed on w1: task 2 ran longer than its task_timeout of 2 s on worker w1: stopped" ||
    { api "/api/v1/jobs/$id"; fail "the job's log does not say task 2 was stopped for its timeout"; }
api "/api/v1/jobs/$id" | grep -q '"worker":"w1","message":"task 2 ran longer than its task_timeout of 2 s' ||
    { api "/api/v1/jobs/$id"; fail "task_errors do not hold the timeout"; }
# The worker killed the hung child (a CANCEL for the task), and stays usable.
wait_log "$TMP/w1.log" "task cancelled: 0 queued and 1 running tasks dropped"
"$GI" workers | grep -q "^w1 .* active" || { "$GI" workers; fail "w1 is not active"; }
! "$GI" workers | grep -q blocklisted || { "$GI" workers; fail "a timeout blocklisted the host"; }
stop_farmd "$LOG"

# 2. No limit in the job: gi-farmd's --task-timeout (2 s) applies. Task 2
# hangs on every run: after 3 (--max-attempts 3) the job fails, saying so.
LOG="$TMP/farmd2.log"
start_farmd "$TMP/state2" "$LOG" -- --heartbeat 0.2 --lease 3 --dead 10 --max-attempts 3 \
    --task-timeout 2 --blocklist-failures 1
start_worker "$TMP/w2.log" env GI_FAULT_HANG_TASK=2:0,2:1,2:2 -- --connect "$WADDR" --procs 2 \
    --cache "$TMP/c2" --name w2
set +e
timeout 120 "$GI" submit "$TMP/job.json" --wait --progress none >"$TMP/wait2.log" 2>&1
rc=$?
set -e
[ $rc -eq 1 ] || { cat "$TMP/wait2.log"; fail "a task that always hangs: exit $rc"; }
grep -q "failed: task 2 failed 3 times; last error: task 2 ran longer than its task_timeout of 2 s on worker w2: stopped" \
    "$TMP/wait2.log" || { cat "$TMP/wait2.log"; fail "no clear error naming the timeout"; }
[ "$(metric gi_farm_task_timeouts_total)" = 3 ] ||
    fail "task_timeouts metric: $(metric gi_farm_task_timeouts_total)"
! "$GI" workers | grep -q blocklisted || { "$GI" workers; fail "timeouts blocklisted the host"; }
stop_farmd "$LOG"

# 3. The limit counts from a run's start, not from its lease. One gi-worker
# with one process and 8 queued slots; every task sleeps 0.8 s before it
# runs (GI_FAULT_SLOW_TASK), so the last of the first 9 waits ~6 s in the
# worker's queue, twice the limit of 3 s: none of them is stopped. Task 2's
# first run hangs: it is stopped (one timeout), while those queued behind it
# wait on. The worker says which tasks run in its heartbeats (protocol 2).
slow=$(seq -s, 0 15) # attempt 0 of every task
LOG="$TMP/farmd3.log"
start_farmd "$TMP/state3" "$LOG" -- --heartbeat 0.2 --lease 3 --dead 10 --max-attempts 3 \
    --task-timeout 3
start_worker "$TMP/w3.log" env GI_FAULT_SLOW_TASK="$slow" GI_FAULT_SLOW_S=0.8 \
    GI_FAULT_HANG_TASK=2:0 -- --connect "$WADDR" --procs 1 --queue 8 --cache "$TMP/c3" --name w3
wait_workers 1
api /api/v1/workers | grep -q '"name":"w3".*"protocol":2' ||
    { api /api/v1/workers; fail "w3 does not speak protocol 2"; }
id=$("$GI" submit "$TMP/job.json" 2>/dev/null) || fail "submit"
# While task 2 hangs: the tasks queued behind it are leased, one runs.
n=0
until api /api/v1/workers | grep -q '"tasks_leased":9,"tasks_running":1,'; do
    n=$((n + 1))
    [ $n -lt 100 ] || { api /api/v1/workers; fail "w3 never held 9 tasks, 1 running"; }
    sleep 0.05
done
timeout 120 "$GI" wait "$id" --out "$TMP/out3" --progress none >"$TMP/wait3.log" 2>&1 ||
    { cat "$TMP/wait3.log"; fail "the job of queued tasks and a hang did not finish"; }
cmp "$TMP/job.json.ref/img.exr" "$TMP/out3/img.exr" || fail "image differs (queued tasks)"
[ "$(jnum "$id" timeouts)" = 1 ] && [ "$(jnum "$id" retries)" = 1 ] ||
    { api "/api/v1/jobs/$id"; fail "queued tasks were stopped, or the hang was not: see timeouts"; }
api "/api/v1/jobs/$id" |
    grep -q "task 2 (attempt 0) failed on w3: task 2 ran longer than its task_timeout of 3 s" ||
    { api "/api/v1/jobs/$id"; fail "the job's log does not say task 2 was stopped"; }
[ "$(metric gi_farm_task_timeouts_total)" = 1 ] ||
    fail "task_timeouts metric: $(metric gi_farm_task_timeouts_total)"
stop_farmd "$LOG"

# 4. A worker of an older build (protocol 1, GI_FAULT_PROTO_MAX=1) does not
# say which tasks run: for it the limit counts from the lease, as that build
# expects, so the same queue sees its waiting tasks stopped.
LOG="$TMP/farmd4.log"
start_farmd "$TMP/state4" "$LOG" -- --heartbeat 0.2 --lease 3 --dead 10 --max-attempts 3 \
    --task-timeout 3
start_worker "$TMP/w4.log" env GI_FAULT_SLOW_TASK="$slow" GI_FAULT_SLOW_S=0.8 \
    GI_FAULT_PROTO_MAX=1 -- --connect "$WADDR" --procs 1 --queue 8 --cache "$TMP/c4" --name w4
wait_workers 1
api /api/v1/workers | grep -q '"name":"w4".*"protocol":1' ||
    { api /api/v1/workers; fail "w4 does not speak protocol 1"; }
grep -q "worker w4 (.*) joined: .*, protocol 1, version" "$LOG" ||
    fail "the log does not say protocol 1"
id=$("$GI" submit "$TMP/job.json" 2>/dev/null) || fail "submit"
n=0
until [ "$(metric gi_farm_task_timeouts_total)" -ge 1 ]; do
    n=$((n + 1))
    [ $n -lt 300 ] || { api "/api/v1/jobs/$id"; fail "no queued task stopped (protocol 1)"; }
    sleep 0.1
done
"$GI" cancel "$id" >/dev/null 2>&1 || fail "cancel"
stop_farmd "$LOG"
echo ok
