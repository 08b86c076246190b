# Task failures on the farm: a worker whose tasks of a job keep failing is
# excluded from that job (not blocklisted: farm_job_exclusions.sh) and the
# others finish the job (identical image); a task that
# fails on every attempt fails its job with the task's error; a task that
# failed on one host is retried on another one; two live workers of one
# name are warned about.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
LOG="$TMP/farmd.log"
start_farmd "$TMP/state" "$LOG" -- --heartbeat 0.2 --lease 3 --dead 10 --blocklist-failures 3 \
    --max-attempts 4
PORTS="--listen-workers $WADDR --listen-api $API"
write_job "$TMP/job.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "pt", "seed": 8,
 "image": {"width": 32, "height": 32}, "pt": {"spp": 32, "tile": 16, "pass_spp": 8},
 "outputs": {"exr": "img.exr"}}
JOB
"$GI_RELEASE" render "$TMP/job.json" --workers 1 --out "$TMP/ref" --progress none >/dev/null 2>&1

# A worker whose children die on task 0 (three attempts in a row, since a
# retry goes first in line): it is excluded from the job (gi status says
# for how long and why), not blocklisted, and a healthy worker then does
# the rest.
start_worker "$TMP/bad.log" env GI_FAULT_CRASH_TASK="0:0,0:1,0:2" -- \
    --connect "$WADDR" --procs 1 --queue 0 --cache "$TMP/c1" --name bad
id=$("$GI" submit "$TMP/job.json" 2>/dev/null) || fail "submit"
wait_log "$LOG" "job $id: worker bad excluded from it for 600 s after 3 of its task failures"
"$GI" status "$id" >"$TMP/status.txt"
grep -q "^  worker bad excluded from this job until .* ([0-9]* s more); last: .*pool child" \
    "$TMP/status.txt" || { cat "$TMP/status.txt"; fail "gi status does not show it excluded"; }
"$GI" workers >"$TMP/workers.txt"
grep -q "^bad .* active " "$TMP/workers.txt" ||
    { cat "$TMP/workers.txt"; fail "one job's failures took the worker out of the farm"; }
start_worker "$TMP/good.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/c2" --name good
wait_state "$id" done 60
"$GI" fetch "$id" --out "$TMP/out" >/dev/null || fail "fetch"
cmp "$TMP/ref/img.exr" "$TMP/out/img.exr" || fail "image differs after the failures"
[ "$(jnum "$id" retries)" -ge 3 ] || fail "retries: $(jnum "$id" retries)"
api "/api/v1/jobs/$id" | grep -q '"worker":"bad","message":"bad: pool child 0' || fail "task errors name the worker"
kill -9 $FARM_PIDS 2>/dev/null || true

# A task that fails every time: the job fails with its error after 4 runs.
start_farmd "$TMP/state" "$LOG" -- --heartbeat 0.2 --lease 3 --dead 10 --blocklist-failures 100 \
    --max-attempts 4 $PORTS
start_worker "$TMP/flaky.log" env GI_FAULT_CRASH_TASK="2:0,2:1,2:2,2:3" -- \
    --connect "$WADDR" --procs 1 --cache "$TMP/c3" --name flaky
set +e
"$GI" submit "$TMP/job.json" --wait --progress none >"$TMP/wait.log" 2>&1
rc=$?
set -e
[ $rc -eq 1 ] || { cat "$TMP/wait.log"; fail "a job whose task always fails: exit $rc"; }
grep -q "failed: task 2 failed 4 times; last error: flaky: pool child 0 .* was killed by signal 9" "$TMP/wait.log" ||
    { cat "$TMP/wait.log"; fail "no clear error"; }

# The same host trouble with a healthy worker beside it: the failed task is
# retried there, not on the host it failed on, and the job is done.
start_worker "$TMP/good2.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/c4" --name good2
wait_workers 2
id=$("$GI" submit "$TMP/job.json" 2>/dev/null) || fail "submit 3"
wait_state "$id" done 60
[ "$(jnum "$id" retries)" = 1 ] || { api "/api/v1/jobs/$id"; fail "task 2 was not retried once, elsewhere"; }
"$GI" fetch "$id" --out "$TMP/out3" >/dev/null || fail "fetch 3"
cmp "$TMP/ref/img.exr" "$TMP/out3/img.exr" || fail "image differs after the retry elsewhere"

# A second live worker of the same name is taken for the same host: said.
start_worker "$TMP/dup.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/c5" --name good2
wait_log "$LOG" "worker good2 (.*) joined while another worker of that name (.*) is active"
stop_farmd "$LOG"
echo ok
