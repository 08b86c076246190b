# Hosts lost with their tasks: a task whose gi-worker is killed (kill -9)
# more times than --max-attempts is requeued each time without counting an
# attempt, and its job finishes with the image of `gi render`; a task lost
# with its host --max-task-losses times fails its job, naming it and the
# hosts; a task whose host goes silent (SIGSTOP) is lost when its lease
# expires, with no attempt counted. The task takes its host down by itself
# (GI_FAULT_KILL_HOST_TASK, GI_FAULT_STOP_HOST_TASK: the pool child that
# gets it signals its gi-worker), so the test needs no timing but a lease
# of 1 s: each gi-worker dies on that task, and the next one is started.
# Losses count towards a host's blocklisting (--blocklist-losses): one loss
# does not blocklist, the host's next result wipes it, a drain loses
# nothing; a host lost 3 times in a row, finishing nothing, is blocklisted.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
cornell_job "$TMP/job.json" 8 32 32 32 8 # 4 tiles x 4 passes: 16 tasks

# hosts NAME SPEC N: N gi-worker in turn (NAME1..NAMEN, one slot each), each
# until its connection ends (the task in SPEC kills it).
hosts() {
    (
        i=1
        while [ "$i" -le "$3" ]; do
            GI_FAULT_KILL_HOST_TASK="$2" "$WORKER" --once --connect "$WADDR" --procs 1 \
                --queue 0 --cache "$TMP/cache-$1" --name "$1$i" >>"$TMP/$1.log" 2>&1 || true
            i=$((i + 1))
        done
    ) &
    FARM_PIDS="$FARM_PIDS $!"
    show_on_failure "$TMP/$1.log"
}

"$FARMD" --state "$TMP/bad" --max-task-losses 0 >"$TMP/flag.log" 2>&1 && fail "a bound of 0"
grep -q -- '--max-task-losses: "0" is not an integer in \[1, 1000\]' "$TMP/flag.log" ||
    { cat "$TMP/flag.log"; fail "no clear error for --max-task-losses 0"; }
"$FARMD" --help | grep -q -- "--max-task-losses N" || fail "--help does not name --max-task-losses"

# 1. Task 2 kills its host on its first 4 runs, twice --max-attempts: the
# fifth host runs it and the job is done, nothing counted as an attempt.
LOG="$TMP/farmd.log"
start_farmd "$TMP/state" "$LOG" -- --heartbeat 0.2 --lease 3 --dead 10 --max-attempts 2
id=$("$GI" submit "$TMP/job.json" 2>/dev/null) || fail "submit"
hosts k "2:0,2:1,2:2,2:3" 5
"$GI" wait "$id" --out "$TMP/out" --progress none >"$TMP/wait1.log" 2>&1 ||
    { cat "$TMP/wait1.log"; fail "the job of a task on 4 lost hosts did not finish"; }
cmp "$TMP/job.json.ref/img.exr" "$TMP/out/img.exr" || fail "image differs after losing 4 hosts"
[ "$(jnum "$id" retries)" = 0 ] || { api "/api/v1/jobs/$id"; fail "losses counted as retries"; }
[ "$(jnum "$id" losses)" = 4 ] || { api "/api/v1/jobs/$id"; fail "losses: $(jnum "$id" losses)"; }
[ "$(metric gi_farm_tasks_lost_total)" = 4 ] || fail "tasks_lost: $(metric gi_farm_tasks_lost_total)"
[ "$(metric gi_farm_task_failures_total)" = 0 ] || fail "losses counted as failures"
api "/api/v1/jobs/$id" | grep -q "task 2 (attempt 3) was lost with its host k4 (loss 4 of 8; requeued, not counted as an attempt): worker k4 (.*) was lost with 1 task" ||
    { api "/api/v1/jobs/$id"; fail "the job's log does not say task 2 was lost and requeued"; }
"$GI" status "$id" | grep -q "0 retries, 4 lost with their host (requeued, not counted)" ||
    { "$GI" status "$id"; fail "gi status does not show the losses"; }
stop_farmd "$LOG"

# 2. Task 1 kills every host it is given: after 3 losses (--max-task-losses
# 3) the job fails, saying which task and on which hosts.
LOG="$TMP/farmd2.log"
start_farmd "$TMP/state2" "$LOG" -- --heartbeat 0.2 --lease 3 --dead 10 --max-task-losses 3
hosts d "1:0,1:1,1:2" 3
set +e
"$GI" submit "$TMP/job.json" --wait --progress none >"$TMP/wait.log" 2>&1
rc=$?
set -e
[ $rc -eq 1 ] || { cat "$TMP/wait.log"; fail "a task that kills its hosts: exit $rc"; }
grep -q "task 1 was lost with its host 3 times (hosts d1, d2, d3): it may be taking its host down; last: worker d3 (.*) was lost with 1 task" \
    "$TMP/wait.log" || { cat "$TMP/wait.log"; fail "no clear error naming the task and hosts"; }
[ "$(metric gi_farm_tasks_lost_total)" = 3 ] || fail "tasks_lost: $(metric gi_farm_tasks_lost_total)"
stop_farmd "$LOG"

# 3. A host gone silent (task 3 SIGSTOPs whichever gi-worker gets it): its
# lease expires, the other host runs the task, and with --max-attempts 1 the
# job is done all the same.
LOG="$TMP/farmd3.log"
start_farmd "$TMP/state3" "$LOG" -- --heartbeat 0.2 --lease 1 --dead 60 --max-attempts 1
start_worker "$TMP/s1.log" env GI_FAULT_STOP_HOST_TASK=3:0 -- --connect "$WADDR" --procs 1 \
    --queue 0 --cache "$TMP/cache-s1" --name s1
S1=$WORKER_PID
start_worker "$TMP/s2.log" env GI_FAULT_STOP_HOST_TASK=3:0 -- --connect "$WADDR" --procs 1 \
    --queue 0 --cache "$TMP/cache-s2" --name s2
S2=$WORKER_PID
wait_workers 2
"$GI" submit "$TMP/job.json" --wait --out "$TMP/out3" --progress none >"$TMP/wait3.log" 2>&1 ||
    { cat "$TMP/wait3.log"; fail "the job of a task on a silent host did not finish"; }
kill -CONT "$S1" "$S2"
cmp "$TMP/job.json.ref/img.exr" "$TMP/out3/img.exr" || fail "image differs after a silent host"
[ "$(jnum 1 lease_expiries)" = 1 ] && [ "$(jnum 1 losses)" = 1 ] && [ "$(jnum 1 retries)" = 0 ] ||
    { api /api/v1/jobs/1; fail "a lease expired on a silent host: not one loss"; }
api /api/v1/jobs/1 | grep -q "task 3 (attempt 0) was lost with its host s[12] (loss 1 of 8; requeued, not counted as an attempt): lease expired on worker s[12]" ||
    { api /api/v1/jobs/1; fail "the job's log does not say the lease expired"; }
stop_farmd "$LOG"

"$FARMD" --state "$TMP/bad" --blocklist-losses 0 >"$TMP/flag.log" 2>&1 &&
    fail "--blocklist-losses 0"
grep -q -- '--blocklist-losses: "0" is not an integer in \[1, 1000000\]' "$TMP/flag.log" ||
    { cat "$TMP/flag.log"; fail "no clear error for --blocklist-losses 0"; }
"$FARMD" --help | grep -q -- "--blocklist-losses N" ||
    fail "--help does not name --blocklist-losses"

# worker_view NAME: the last entry of GET /api/v1/workers for NAME.
worker_view() {
    api /api/v1/workers | grep -o "{[^{}]*\"name\":\"$1\"[^{}]*}" | tail -n 1
}

# 4. Losses and blocklisting (--blocklist-losses 3). Host "flaky" dies once
# (task 2 kills it), comes back under its name and finishes the job: one
# loss, wiped by its results, no blocklisting.
LOG="$TMP/farmd4.log"
start_farmd "$TMP/state4" "$LOG" -- --heartbeat 0.2 --lease 3 --dead 10 --blocklist-losses 3
id=$("$GI" submit "$TMP/job.json" 2>/dev/null) || fail "submit"
GI_FAULT_KILL_HOST_TASK=2:0 "$WORKER" --once --connect "$WADDR" --procs 1 --queue 0 \
    --cache "$TMP/cache-flaky" --name flaky >>"$TMP/flaky.log" 2>&1 || true
n=0
until [ "$(metric gi_farm_host_losses_total)" = 1 ]; do
    n=$((n + 1))
    [ $n -lt 100 ] || fail "host losses after flaky died: $(metric gi_farm_host_losses_total)"
    sleep 0.1
done
# Every task of this incarnation sleeps 0.3 s first, so it still holds one
# when told to drain below.
start_worker "$TMP/flaky.log" env GI_FAULT_SLOW_TASK="$(seq -s, 0 15)" GI_FAULT_SLOW_S=0.3 -- \
    --connect "$WADDR" --procs 1 --queue 0 --cache "$TMP/cache-flaky" --name flaky
FLAKY=$WORKER_PID
"$GI" wait "$id" --out "$TMP/out4" --progress none >"$TMP/wait4.log" 2>&1 ||
    { cat "$TMP/wait4.log"; fail "the job of a host lost once did not finish"; }
cmp "$TMP/job.json.ref/img.exr" "$TMP/out4/img.exr" || fail "image differs after a host lost once"
v=$(worker_view flaky)
echo "$v" | grep -q '"state":"active".*"losses":1,"consecutive_losses":0,' ||
    fail "flaky after one loss and its results: $v"
# A drain loses nothing: SIGTERM while flaky runs a task of a second job.
id2=$("$GI" submit "$TMP/job.json" 2>/dev/null) || fail "submit"
wait_merged "$id2" 16
kill -TERM "$FLAKY"
wait "$FLAKY" || fail "flaky did not drain cleanly"
grep -q "draining: 0 queued tasks handed back, finishing 1 running ones" "$TMP/flaky.log" ||
    fail "flaky held no task when it drained"
wait_log "$LOG" "worker flaky (.*) left: said goodbye"
[ "$(metric gi_farm_host_losses_total)" = 1 ] ||
    fail "a drain counted as a loss: $(metric gi_farm_host_losses_total)"
# Host "bad" dies on every task it gets: after its third loss in a row,
# nothing finished in between, it is blocklisted; its fourth incarnation
# gets no task, and host "good" finishes the job.
spec=$(for t in $(seq 0 15); do for a in $(seq 0 9); do printf '%s:%s,' "$t" "$a"; done; done)
(
    for i in 1 2 3 4; do
        GI_FAULT_KILL_HOST_TASK="$spec" "$WORKER" --once --connect "$WADDR" --procs 1 \
            --queue 0 --cache "$TMP/cache-bad" --name bad >>"$TMP/bad.log" 2>&1 || true
    done
) &
FARM_PIDS="$FARM_PIDS $!"
show_on_failure "$TMP/bad.log"
wait_log "$LOG" "worker bad blocklisted for 600 s after 3 losses with tasks held (no result in \
between) in a row; last: lost with 1 task"
[ "$(metric gi_farm_host_losses_total)" = 4 ] ||
    fail "host losses: $(metric gi_farm_host_losses_total)"
n=0
until worker_view bad | grep -q '"state":"blocklisted"'; do
    n=$((n + 1))
    [ $n -lt 100 ] || { api /api/v1/workers; fail "bad's fourth run is not listed blocklisted"; }
    sleep 0.1
done
v=$(worker_view bad)
echo "$v" | grep -q '"tasks_leased":0,.*"losses":3,"consecutive_losses":3,' ||
    fail "bad after 3 losses: $v"
[ "$(metric 'gi_farm_workers{state="blocklisted"}')" = 1 ] ||
    { api /metrics; fail "no blocklisted worker in the metrics"; }
start_worker "$TMP/good.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/cache-good" --name good
"$GI" wait "$id2" --out "$TMP/out5" --progress none >"$TMP/wait5.log" 2>&1 ||
    { cat "$TMP/wait5.log"; fail "the job did not finish on the good host"; }
cmp "$TMP/job.json.ref/img.exr" "$TMP/out5/img.exr" || fail "image differs after a blocklisted host"
worker_view bad | grep -q '"tasks_done":0,' ||
    fail "the blocklisted host ran a task: $(worker_view bad)"
stop_farmd "$LOG"
echo "ok: 4 hosts lost under one task, job done and identical; a host killer fails its job;"
echo "a silent host's lease expired without an attempt counted; a host lost three times in"
echo "a row is blocklisted, one lost once or drained is not"
