# Wrong answers on the farm, end to end: a worker that sends results its
# method's check refuses (GI_FAULT_BAD_RESULT_TASK: the runs named send
# their result one byte short, a well-formed RESULT with a cut payload).
# 1. For every method with a check (pt, detp still and animation,
#    quadrature, radiosity), a tiny job whose runs 0, 3 and 7 (attempt 0)
#    are damaged: each is refused and retried (the job's view: retries,
#    task_errors and log; gi status; gi submit --wait; the failures metric;
#    the worker's tasks_failed), the coordinator's log names the job, the
#    task and why, the job ends done, and its outputs equal, byte for byte,
#    the same job's on a clean farm.
# 2. A worker that damages every result: the first task fails after
#    --max-attempts runs, the job fails at once (no hang) saying which task
#    and why.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
S="$SRC/scenes/cornell-box"
# Task ids (plan order): pt: 4 tiles (0-3). detp: 4 photon batches (0-3),
# then 9 image tiles (4-12). The animation: frame 0's 2 batches (0-1) and 4
# tiles (2-5), frame 1's 2 update batches (6-7) and 4 tiles (8-11).
# quadrature: region tasks (16 in all). radiosity: 1 form-factor block (0),
# then 9 image tiles (1-9). So 0, 3 and 7 hit every kind of result but
# detp's reference and visibility values (unit tests refuse those).
write_job "$TMP/pt.json" <<JOB
{"scene": "$S/scene.json", "method": "pt", "seed": 8, "image": {"width": 32, "height": 32},
 "pt": {"spp": 8, "tile": 16, "pass_spp": 8}, "outputs": {"exr": "img.exr"}}
JOB
write_job "$TMP/detp.json" <<JOB
{"scene": "$S/scene.json", "method": "detp", "seed": 3, "image": {"width": 24, "height": 24},
 "detp": {"photons": 20000, "batch": 5000, "subdivide": 40, "tile": 8, "image_spp": 1},
 "outputs": {"exr": "detp.exr", "ply": "detp.ply", "bin": "detp.bin"}}
JOB
write_job "$TMP/anim.json" <<JOB
{"scene": "$S/scene-mobile.json", "method": "detp", "seed": 5,
 "image": {"width": 16, "height": 12},
 "detp": {"photons": 6000, "batch": 3000, "subdivide": "14%", "tile": 8, "image_spp": 1,
          "animation": {"object": "mobile", "frames": 2,
                        "keyframes": [{"frame": 0, "translate": [340, -338.9, -90]},
                                      {"frame": 1, "translate": [248, -338.9, -0.4]}]}},
 "outputs": {"exr": "img.exr", "bin": "v.bin"}}
JOB
write_job "$TMP/quad.json" <<JOB
{"scene": "$S/scene.json", "method": "quadrature", "image": {"width": 24, "height": 24},
 "quadrature": {"dims": 4, "rule": "boole", "max_evals": 40000},
 "outputs": {"exr": "quad.exr"}}
JOB
write_job "$TMP/rad.json" <<JOB
{"scene": "$S/scene.json", "method": "radiosity", "image": {"width": 24, "height": 24},
 "radiosity": {"patches": 40, "levels": 1, "rays": 256, "tile": 8},
 "outputs": {"exr": "rad.exr", "ply": "rad.ply"}}
JOB
JOBS="pt detp anim quad rad"
# Why each damaged run is refused: "JOB:TASK:what the check says".
WHY="pt:0:result has 8191 bytes, expected 8192
pt:3:result has 8191 bytes, expected 8192
detp:0:detp result: bad entry 
detp:3:detp result: bad entry 
detp:7:tile result has 
anim:0:frame 0, batch 0: detp animation result: bad entry 
anim:3:tile result has 
anim:7:frame 1, batch 1: detp animation result: bad entry 
quad:0:quadrature result: bad region count
quad:3:quadrature result: bad region count
quad:7:quadrature result: bad region count
rad:0:radiosity: row of element 247 is malformed
rad:3:tile result has 767 bytes, expected 768
rad:7:tile result has 767 bytes, expected 768"
LOG="$TMP/farmd.log"
OPTS="--heartbeat 0.2 --lease 5 --dead 20 --max-attempts 3 --blocklist-failures 100"
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$LOG" -- $OPTS

# run_job NAME FARM: NAME's job submitted and waited for, its outputs into
# $TMP/FARM-NAME, gi's output into $TMP/FARM-NAME.log.
run_job() {
    "$GI" submit "$TMP/$1.json" --wait --out "$TMP/$2-$1" --progress none >"$TMP/$2-$1.log" 2>&1 ||
        { cat "$TMP/$2-$1.log"; fail "$1 on the $2 farm"; }
}

# 1. The clean farm's outputs, then the same jobs with a damaging worker.
start_worker "$TMP/clean.log" -- --connect "$WADDR" --procs 2 --cache "$TMP/c-clean" --name clean
clean_pid=$WORKER_PID
for j in $JOBS; do
    run_job "$j" clean
    ! grep -q retried "$TMP/clean-$j.log" || { cat "$TMP/clean-$j.log"; fail "$j retried when clean"; }
done
kill "$clean_pid"
wait "$clean_pid" 2>/dev/null || true
start_worker "$TMP/bad.log" env GI_FAULT_BAD_RESULT_TASK=0,3,7 -- --connect "$WADDR" --procs 2 \
    --cache "$TMP/c-bad" --name bad
failures0=$(metric gi_farm_task_failures_total)
damaged=0
for j in $JOBS; do
    run_job "$j" bad
    id=$(sed -n "s/^.*: job \([0-9]*\) (.*) done on the farm$/\1/p" "$TMP/bad-$j.log")
    [ -n "$id" ] || { cat "$TMP/bad-$j.log"; fail "$j: no job id in gi submit --wait's summary"; }
    n=$(echo "$WHY" | grep -c "^$j:")
    damaged=$((damaged + n))
    grep -q "tasks, $n retried$" "$TMP/bad-$j.log" ||
        { cat "$TMP/bad-$j.log"; fail "$j: gi does not say $n retried"; }
    [ "$(jstate "$id")" = done ] || fail "$j: job $id is $(jstate "$id")"
    [ "$(jnum "$id" retries)" = "$n" ] || { api "/api/v1/jobs/$id"; fail "$j: retries not $n"; }
    "$GI" status "$id" >"$TMP/status-$j.txt"
    while IFS=: read -r _ t why; do
        msg="task $t's result: $why"
        grep -qF "job $id: task $t (attempt 0) failed on bad: $msg" "$LOG" ||
            fail "$j: the coordinator's log does not say job $id's task $t failed: $msg"
        api "/api/v1/jobs/$id" >"$TMP/view.json"
        grep -qF "\"task\":$t,\"attempt\":0,\"worker\":\"bad\",\"message\":\"$msg" "$TMP/view.json" ||
            { cat "$TMP/view.json"; fail "$j: task $t's refusal is not in its task_errors"; }
        grep -qF "task $t (attempt 0) failed on bad: $msg" "$TMP/view.json" ||
            { cat "$TMP/view.json"; fail "$j: task $t's refusal is not in the job's log"; }
        grep -qF "task $t attempt 0 on bad: $msg" "$TMP/status-$j.txt" ||
            { cat "$TMP/status-$j.txt"; fail "$j: gi status does not show task $t's refusal"; }
        grep -q "fault injection: task $t's result is sent one byte short" "$TMP/bad.log" ||
            fail "$j: the worker did not damage task $t"
    done <<EOF
$(echo "$WHY" | grep "^$j:")
EOF
    for f in "$TMP/clean-$j"/*; do
        cmp "$f" "$TMP/bad-$j/$(basename "$f")" || fail "$j: $(basename "$f") differs from the clean one"
    done
done
[ "$(metric gi_farm_task_failures_total)" = $((failures0 + damaged)) ] ||
    fail "failures counted: $(metric gi_farm_task_failures_total), not $failures0 + $damaged"
api /api/v1/workers | grep -q '"name":"bad",[^}]*"tasks_failed":'"$damaged"',' ||
    { api /api/v1/workers; fail "the worker's tasks_failed is not $damaged"; }
kill "$WORKER_PID"
wait "$WORKER_PID" 2>/dev/null || true

# 2. Every result damaged: task 0 fails 3 times (one process, no queue: its
# retries come first), and the job fails with its last refusal.
start_worker "$TMP/all.log" env GI_FAULT_BAD_RESULT_TASK='*' -- --connect "$WADDR" --procs 1 \
    --queue 0 --cache "$TMP/c-all" --name all-bad
st=0
timeout 60 "$GI" submit "$TMP/pt.json" --wait --progress none >"$TMP/all-wait.log" 2>&1 || st=$?
[ $st -eq 1 ] || { cat "$TMP/all-wait.log"; fail "a job whose results are all damaged: exit $st"; }
why="task 0 failed 3 times; last error: task 0's result: result has 8191 bytes, expected 8192"
grep -qF "failed: $why" "$TMP/all-wait.log" || { cat "$TMP/all-wait.log"; fail "no clear error"; }
grep -qF "$why" "$LOG" || fail "the coordinator's log does not say why the job failed"
stop_farmd "$LOG"
echo "damaged results of every method refused and retried ($damaged runs); outputs as when clean"
