# Whose fault is a task failure, the host's or the job's (docs/farm.md,
# "Fault tolerance", "Blame"):
# (a) Two broken jobs at once (their tasks 10-15 crash on every host) on a
#     3-worker farm: their failures are never held against a host, so no
#     worker is blocklisted, and a good job submitted with them is done.
# (b) A bad host (every run crashes): alone, it is only excluded from each
#     job (nothing to compare it with); once a healthy host has run the
#     tasks it failed, of two jobs, it is blocklisted, and gi workers (its
#     OWNFAIL column: the API's own_failures) and /metrics say so.
# (c) A worker excluded from a broken job A that then fails a task of a
#     job B is not blocklisted.
# (d) A job's failure on another host long ago (more than
#     --blocklist-seconds before) does not excuse a bad host's failures of
#     it: the bad host failing that job and another, whose tasks a healthy
#     host then runs, is blocklisted.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
# Broken jobs: 4 tiles x 4 passes = 16 tasks; good jobs: 4 tasks (0-3).
cornell_job "$TMP/broken.json" 8 32 32 32
cornell_job "$TMP/good.json" 9 32 32 8
render_refs good

BROKEN="$(fault_runs 10 11 12 13 14 15)"


stop_workers() {
    for w in $WORKER_PIDS; do kill "$w" 2>/dev/null || true; done
    for w in $WORKER_PIDS; do wait "$w" 2>/dev/null || true; done
    WORKER_PIDS=""
}

# (a) Two broken jobs and a good one at once.
LOG="$TMP/farmd-a.log"
start_farmd "$TMP/state-a" "$LOG" -- --heartbeat 0.2 --lease 5 --dead 10 --blocklist-failures 2 \
    --blocklist-seconds 3 --max-attempts 4
for w in w1 w2 w3; do
    start_worker "$TMP/a-$w.log" env "GI_FAULT_CRASH_TASK=$BROKEN" -- --connect "$WADDR" \
        --procs 1 --queue 0 --cache "$TMP/ca-$w" --name "$w"
done
wait_workers 3
a1=$("$GI" submit "$TMP/broken.json" 2>/dev/null) || fail "submit A1"
a2=$("$GI" submit "$TMP/broken.json" 2>/dev/null) || fail "submit A2"
g=$("$GI" submit "$TMP/good.json" 2>/dev/null) || fail "submit G"
wait_state "$g" done 60
"$GI" fetch "$g" --out "$TMP/out-g" >/dev/null || fail "fetch G"
cmp "$TMP/ref-good/img.exr" "$TMP/out-g/img.exr" || fail "G's image differs"
wait_state "$a1" failed 90
wait_state "$a2" failed 90
# Workers failed the tasks of both broken jobs (what blocklisted them
# before: a streak of two jobs' failures); which ones is up to timing.
both=0
for w in w1 w2 w3; do
    grep -q "job $a1: task 1[0-5] (attempt [0-9]*) failed on $w" "$LOG" &&
        grep -q "job $a2: task 1[0-5] (attempt [0-9]*) failed on $w" "$LOG" && both=$((both + 1))
done
[ $both -ge 2 ] || fail "$both workers failed the tasks of both broken jobs: nothing tested"
! grep -q "blocklisted for" "$LOG" || { grep "blocklisted for" "$LOG"; fail "(a): blocklisted"; }
[ "$(metric 'gi_farm_workers{state="blocklisted"}')" = 0 ] || fail "(a): blocklisted workers"
[ "$(metric gi_farm_task_failures_host_total)" = 0 ] ||
    fail "(a): failures held against a host: $(metric gi_farm_task_failures_host_total)"
[ "$(metric gi_farm_task_failures_total)" -ge 8 ] ||
    fail "(a): only $(metric gi_farm_task_failures_total) failures"
api /api/v1/workers | grep -q '"consecutive_failures":[1-9]' &&
    { api /api/v1/workers; fail "(a): a worker has a streak of its own failures"; }
stop_farmd "$LOG"
stop_workers

# (b) A bad host, alone and then beside a healthy one.
LOG="$TMP/farmd-b.log"
start_farmd "$TMP/state-b" "$LOG" -- --heartbeat 0.2 --lease 5 --dead 10 --blocklist-failures 3 \
    --blocklist-seconds 600 --max-attempts 20
start_worker "$TMP/bad.log" env "GI_FAULT_CRASH_TASK=*" -- --connect "$WADDR" --procs 1 \
    --queue 0 --cache "$TMP/c-bad" --name bad
wait_workers 1
c=$("$GI" submit "$TMP/good.json" 2>/dev/null) || fail "submit C"
d=$("$GI" submit "$TMP/good.json" 2>/dev/null) || fail "submit D"
n=0
until [ "$(excluded "$c")" = "bad " ] && [ "$(excluded "$d")" = "bad " ]; do
    n=$((n + 1))
    [ $n -lt 300 ] || { api "/api/v1/jobs/$d"; fail "bad was not excluded from C and D"; }
    sleep 0.05
done
# Alone, nothing says it is the host and not the jobs: not blocklisted.
! grep -q "blocklisted for" "$LOG" || fail "(b): a lone host was blocklisted"
[ "$(metric gi_farm_task_failures_host_total)" = 0 ] || fail "(b): judged with nothing to compare"
start_worker "$TMP/healthy.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/c-healthy" \
    --name healthy
wait_state "$c" done 60
wait_state "$d" done 60
wait_log "$LOG" "worker bad blocklisted for 600 s after [0-9]* task failures of its own (tasks \
of more than one job that other hosts ran, or its disk's) in a row; last: bad: pool child"
grep -c "blocklisted for" "$LOG" | grep -q '^1$' || fail "(b): not one host blocklisted once"
"$GI" workers >"$TMP/workers-b.txt"
grep -A1 "^bad .*blocklisted" "$TMP/workers-b.txt" |
    grep -q "^    for [0-9]* s more; last: .*pool child" ||
    { cat "$TMP/workers-b.txt"; fail "gi workers does not show bad blocklisted, how long and why"; }
# Its OWNFAIL column is the API's own_failures (>= 6: those that blocklisted it).
own=$(api /api/v1/workers | tr '{' '\n' | grep '"name":"bad"' | grep -o '"own_failures":[0-9]*' |
    cut -d: -f2)
col=$(awk 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "OWNFAIL") c = i }
           $1 == "bad" { print $c }' "$TMP/workers-b.txt")
[ -n "$own" ] && [ "$own" -ge 6 ] && [ "$col" = "$own" ] ||
    { cat "$TMP/workers-b.txt"; fail "gi workers: bad's OWNFAIL is \"$col\", own_failures $own"; }
grep -q "^healthy .* active " "$TMP/workers-b.txt" ||
    { cat "$TMP/workers-b.txt"; fail "the healthy worker is not active"; }
[ "$(metric gi_farm_task_failures_host_total)" -ge 6 ] ||
    fail "(b): $(metric gi_farm_task_failures_host_total) failures judged the host's, not >= 6"
[ "$(metric 'gi_farm_workers{state="blocklisted"}')" = 1 ] || fail "(b): no blocklisted worker"
"$GI" fetch "$d" --out "$TMP/out-d" >/dev/null || fail "fetch D"
cmp "$TMP/ref-good/img.exr" "$TMP/out-d/img.exr" || fail "D's image differs"
stop_farmd "$LOG"
stop_workers

# (c) Excluded from broken job A, then a failure of job B.
LOG="$TMP/farmd-c.log"
start_farmd "$TMP/state-c" "$LOG" -- --heartbeat 0.2 --lease 5 --dead 10 --blocklist-failures 2 \
    --blocklist-seconds 600 --max-attempts 20
for w in x y; do
    start_worker "$TMP/c-$w.log" env "GI_FAULT_CRASH_TASK=$BROKEN" -- --connect "$WADDR" \
        --procs 1 --queue 0 --cache "$TMP/cc-$w" --name "$w"
    eval "pid_$w=\$WORKER_PID"
done
wait_workers 2
a=$("$GI" submit "$TMP/broken.json" 2>/dev/null) || fail "submit A"
n=0
until [ "$(excluded "$a")" = "x y " ]; do
    n=$((n + 1))
    [ $n -lt 300 ] || { api "/api/v1/jobs/$a"; fail "x and y were not excluded from A"; }
    sleep 0.05
done
# x comes back (it held nothing: a drain) failing the first run of any of
# B's tasks; A's tasks 0-3 are done, so only B's runs are hit.
kill -TERM "$pid_x"
wait "$pid_x" 2>/dev/null || true
start_worker "$TMP/c-x2.log" env "GI_FAULT_CRASH_TASK=$BROKEN,0:0,1:0,2:0,3:0" -- \
    --connect "$WADDR" --procs 1 --queue 0 --cache "$TMP/cc-x" --name x
wait_workers 2
b=$("$GI" submit "$TMP/good.json" 2>/dev/null) || fail "submit B"
wait_state "$b" done 60
grep -q "job $b: task [0-3] (attempt 0) failed on x" "$LOG" ||
    { tail -n 30 "$LOG"; fail "(c): x failed none of B's tasks: nothing tested"; }
! grep -q "blocklisted for" "$LOG" || { grep "blocklisted for" "$LOG"; fail "(c): blocklisted"; }
"$GI" workers | grep -q "^x .* active " || { "$GI" workers; fail "(c): x is not active"; }
[ "$(excluded "$a")" = "x y " ] || fail "(c): the exclusions from A ended"
"$GI" fetch "$b" --out "$TMP/out-b" >/dev/null || fail "fetch B"
cmp "$TMP/ref-good/img.exr" "$TMP/out-b/img.exr" || fail "B's image differs"
stop_farmd "$LOG"
stop_workers

# (d) Job C fails once on flaky (its task 0's first run), which then
# returns results; more than the window later, bad fails C and D.
LOG="$TMP/farmd-d.log"
start_farmd "$TMP/state-d" "$LOG" -- --heartbeat 0.2 --lease 5 --dead 10 --blocklist-failures 2 \
    --blocklist-seconds 4 --max-attempts 40
start_worker "$TMP/flaky.log" env GI_FAULT_CRASH_TASK=0:0 GI_FAULT_SLOW_TASK='*' \
    GI_FAULT_SLOW_S=0.5 -- --connect "$WADDR" --procs 1 --queue 0 --cache "$TMP/cd-flaky" \
    --name flaky
wait_workers 1
c=$("$GI" submit "$TMP/broken.json" 2>/dev/null) || fail "submit C"
wait_log "$LOG" "job $c: task 0 (attempt 0) failed on flaky"
n=0
until [ "$(jnum "$c" merged)" -ge 1 ]; do
    n=$((n + 1))
    [ $n -lt 300 ] || fail "(d): flaky returned no result of C"
    sleep 0.05
done
sleep 4.5
kill -TERM "$WORKER_PID"
wait "$WORKER_PID" 2>/dev/null || true
[ "$(jnum "$c" merged)" -lt 16 ] || fail "(d): C is done before the bad host came"
start_worker "$TMP/bad-d.log" env "GI_FAULT_CRASH_TASK=*" -- --connect "$WADDR" --procs 1 \
    --queue 0 --cache "$TMP/cd-bad" --name bad
wait_log "$LOG" "job $c: worker bad excluded from it"
d=$("$GI" submit "$TMP/good.json" 2>/dev/null) || fail "submit D"
wait_log "$LOG" "job $d: worker bad excluded from it"
start_worker "$TMP/healthy-d.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/cd-healthy" \
    --name healthy
wait_state "$c" done 60
wait_state "$d" done 60
wait_log "$LOG" "worker bad blocklisted for 4 s after [0-9]* task failures of its own"
! grep -q "worker \(flaky\|healthy\) blocklisted" "$LOG" || fail "(d): a good host blocklisted"
stop_farmd "$LOG"
stop_workers
echo ok
