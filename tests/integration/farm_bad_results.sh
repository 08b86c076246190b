# Wrong answers on the farm, end to end: a worker that sends results its
# method's check refuses (GI_FAULT_BAD_RESULT_TASK names the runs damaged,
# GI_FAULT_BAD_RESULT_KIND how: cut one byte short, a NaN in place of the
# first floating-point value, or a value that would overflow the sums it
# goes into; each a well-formed RESULT).
# 1. For every method with a check (pt, detp still and animation,
#    quadrature, radiosity) and every kind of damage, a tiny job whose runs
#    0, 3 and 7 (attempt 0) are damaged: each is refused and retried (the
#    job's view: retries, task_errors and log; gi status; gi submit --wait;
#    the failures metric; the worker's tasks_failed), the coordinator's log
#    names the job, the task and why, the job ends done, and its outputs
#    equal, byte for byte, the same job's on a clean farm. A run whose
#    result has no value that kind of damage applies to (a NaN in integer
#    sums, a huge pixel that is placed, not summed) is sent as it is, and
#    the worker says so.
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
# Why each damaged run is refused: "KIND:JOB:TASK:what the check says" (the
# start of it); "KIND:JOB:TASK:-": the result is sent as it is.
WHY="short:pt:0:result has 8191 bytes, expected 8192
short:pt:3:result has 8191 bytes, expected 8192
short:detp:0:detp result: bad entry 
short:detp:3:detp result: bad entry 
short:detp:7:tile result has 
short:anim:0:frame 0, batch 0: detp animation result: bad entry 
short:anim:3:tile result has 
short:anim:7:frame 1, batch 1: detp animation result: bad entry 
short:quad:0:quadrature result: bad region count
short:quad:3:quadrature result: bad region count
short:quad:7:quadrature result: bad region count
short:rad:0:radiosity: row of element 247 is malformed
short:rad:3:tile result has 767 bytes, expected 768
short:rad:7:tile result has 767 bytes, expected 768
nan:pt:0:pixel (0, 0) is not finite (nan)
nan:pt:3:pixel (16, 16) is not finite (nan)
nan:detp:0:detp result: vertex 
nan:detp:3:detp result: vertex 
nan:detp:7:pixel (0, 8) is not finite (nan)
nan:anim:0:-
nan:anim:3:pixel (8, 0) is not finite (nan)
nan:anim:7:-
nan:quad:0:quadrature result: the red estimate change is nan, not within +-1e+280
nan:quad:3:quadrature result: the red estimate change is nan, not within +-1e+280
nan:quad:7:quadrature result: the red estimate change is nan, not within +-1e+280
nan:rad:0:-
nan:rad:3:pixel (16, 0) is not finite (nan)
nan:rad:7:pixel (0, 16) is not finite (nan)
huge:pt:0:pixel (0, 0)'s red sum is 1e+300, out of range for 8 samples
huge:pt:3:pixel (16, 16)'s red sum is 1e+300, out of range for 8 samples
huge:detp:0:detp result: vertex 
huge:detp:3:detp result: vertex 
huge:detp:7:-
huge:anim:0:frame 0, batch 0: detp animation result: vertex 
huge:anim:3:-
huge:anim:7:frame 1, batch 1: detp animation result: vertex 
huge:quad:0:quadrature result: pixel 
huge:quad:3:quadrature result: pixel 
huge:quad:7:quadrature result: pixel 
huge:rad:0:radiosity: row of element 0 has d2 18446744073709551615, above its sum of
huge:rad:3:-
huge:rad:7:-"
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
failures0=$(metric gi_farm_task_failures_total)
damaged=0
for kind in short nan huge; do
    w=bad-$kind
    start_worker "$TMP/$w.log" env GI_FAULT_BAD_RESULT_TASK=0,3,7 GI_FAULT_BAD_RESULT_KIND=$kind \
        -- --connect "$WADDR" --procs 2 --cache "$TMP/c-$w" --name "$w"
    refused=0
    for j in $JOBS; do
        run_job "$j" "$w"
        out="$TMP/$w-$j"
        id=$(sed -n "s/^.*: job \([0-9]*\) (.*) done on the farm$/\1/p" "$out.log")
        [ -n "$id" ] || { cat "$out.log"; fail "$j ($kind): no job id in gi submit's summary"; }
        n=$(echo "$WHY" | grep "^$kind:$j:" | grep -vc ':-$' || true)
        refused=$((refused + n))
        if [ "$n" -gt 0 ]; then
            grep -q "tasks, $n retried$" "$out.log" ||
                { cat "$out.log"; fail "$j ($kind): gi does not say $n retried"; }
        else
            ! grep -q retried "$out.log" || { cat "$out.log"; fail "$j ($kind): retried"; }
        fi
        [ "$(jstate "$id")" = done ] || fail "$j ($kind): job $id is $(jstate "$id")"
        [ "$(jnum "$id" retries)" = "$n" ] ||
            { api "/api/v1/jobs/$id"; fail "$j ($kind): retries not $n"; }
        "$GI" status "$id" >"$out-status.txt"
        api "/api/v1/jobs/$id" >"$out-view.json"
        while IFS=: read -r _ _ t why; do
            if [ "$why" = - ]; then
                grep -q "fault injection: task $t's result has no value .* sent as it is" \
                    "$TMP/$w.log" || fail "$j ($kind): the worker does not say task $t went as is"
                continue
            fi
            msg="task $t's result: $why"
            grep -qF "job $id: task $t (attempt 0) failed on $w: $msg" "$LOG" ||
                fail "$j ($kind): the coordinator's log does not say task $t failed: $msg"
            grep -qF "\"task\":$t,\"attempt\":0,\"worker\":\"$w\",\"message\":\"$msg" \
                "$out-view.json" ||
                { cat "$out-view.json"; fail "$j ($kind): task $t's refusal not in task_errors"; }
            grep -qF "task $t (attempt 0) failed on $w: $msg" "$out-view.json" ||
                { cat "$out-view.json"; fail "$j ($kind): task $t's refusal not in the job's log"; }
            grep -qF "task $t attempt 0 on $w: $msg" "$out-status.txt" ||
                { cat "$out-status.txt"; fail "$j ($kind): gi status lacks task $t's refusal"; }
            grep -q "fault injection: task $t's result is sent \(one byte short\|with \)" \
                "$TMP/$w.log" || fail "$j ($kind): the worker did not damage task $t"
        done <<EOF
$(echo "$WHY" | grep "^$kind:$j:")
EOF
        for f in "$TMP/clean-$j"/*; do
            cmp "$f" "$out/$(basename "$f")" ||
                fail "$j ($kind): $(basename "$f") differs from the clean one"
        done
    done
    api /api/v1/workers | grep -q '"name":"'"$w"'",[^}]*"tasks_failed":'"$refused"',' ||
        { api /api/v1/workers; fail "$w's tasks_failed is not $refused"; }
    damaged=$((damaged + refused))
    kill "$WORKER_PID"
    wait "$WORKER_PID" 2>/dev/null || true
done
[ "$(metric gi_farm_task_failures_total)" = $((failures0 + damaged)) ] ||
    fail "failures counted: $(metric gi_farm_task_failures_total), not $failures0 + $damaged"

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
echo "bad results (short, NaN, huge) refused and retried ($damaged runs); outputs as when clean"
