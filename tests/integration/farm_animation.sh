# detp animation on the farm (issue 7): two worker hosts with their own
# batch stores. Batches stick to the host that holds them; when one host is
# killed in the middle of the animation its batches move to the other, which
# regenerates them from their seeds, and every frame is byte-identical to
# `gi render`. The same across a kill -9 and restart of the coordinator. A
# worker away when a job ended removes its batches when it comes back; a
# failed job's batches are kept for its retry.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
write_job "$TMP/job.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene-mobile.json", "method": "detp", "seed": 11,
 "image": {"width": 32, "height": 32},
 "detp": {"photons": 400000, "batch": 50000, "subdivide": 40, "tile": 16, "image_spp": 1,
          "animation": {"object": "mobile", "frames": 8,
                        "keyframes": [{"frame": 0, "translate": [340, -338.9, -90]},
                                      {"frame": 7, "translate": [248, -338.9, -0.4]}]}},
 "outputs": {"exr": "img.exr", "bin": "v.bin", "json": "report.json"}}
JOB
"$GI_RELEASE" render "$TMP/job.json" --workers 2 --out "$TMP/ref" --progress none >/dev/null 2>&1 ||
    fail "gi render"
same_as_ref() { # same_as_ref DIR WHAT
    for f in 0000 0001 0002 0003 0004 0005 0006 0007; do
        for k in img.$f.exr v.$f.bin; do
            cmp "$TMP/ref/$k" "$1/$k" || fail "$2: $k differs from gi render"
        done
    done
}
# wait_merged_tasks ID N: until N tasks are merged (the animation adds each
# frame's tasks as it goes, so the total grows).
wait_merged_tasks() {
    n=0
    until [ "$(jnum "$1" merged)" -ge "$2" ] 2>/dev/null; do
        n=$((n + 1))
        [ $n -lt 1200 ] || fail "job $1 did not reach $2 merged tasks"
        sleep 0.05
    done
    unended "$1" || fail "job $1 ended too soon; make it longer"
}

OPTS="--heartbeat 0.2 --lease 3 --dead 3 --checkpoint 0.2"
LOG="$TMP/farmd.log"
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$LOG" -- $OPTS
PORTS="--listen-workers $WADDR --listen-api $API"
start_worker "$TMP/a.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/ca" --name a
A_PID=$WORKER_PID
start_worker "$TMP/b.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/cb" --name b
wait_workers 2

# Frame 0 is 12 tasks (8 batches, 4 tiles), every frame after it too.
id=$("$GI" submit "$TMP/job.json" 2>"$TMP/submit.log") || { cat "$TMP/submit.log"; fail "submit"; }
wait_merged_tasks "$id" 30
# Progress by frames: frame 2 or later of 8, with an ETA from the frames seen.
view=$(api "/api/v1/jobs/$id")
echo "$view" | grep -q '"frame":[2-7],"frames":8' || fail "no frame of 8 in the job view: $view"
echo "$view" | grep -q '"eta_seconds":[0-9]' || fail "no ETA at frame 2 or later: $view"
ls "$TMP"/ca/batches/*/b*.f* >/dev/null 2>&1 || fail "worker a holds no batch files"
kill -9 "$A_PID"
wait_state "$id" done 300
view=$(api "/api/v1/jobs/$id")
for want in '"progress":1,' '"eta_seconds":0,' '"frame":7,"frames":8'; do
    echo "$view" | grep -q "$want" || fail "done job's view lacks $want: $view"
done
"$GI" fetch "$id" --out "$TMP/killed" >/dev/null || fail "fetch"
same_as_ref "$TMP/killed" "worker killed"
grep -q "affinity key .* moves from worker a to worker b" "$LOG" || fail "no batch moved to worker b"
regen=0
for r in "$TMP"/killed/report.000*.json; do
    n=$(sed -n 's/.*"frames_regenerated":[^0-9]*\([0-9]*\).*/\1/p' "$r")
    regen=$((regen + n))
done
[ "$regen" -gt 0 ] || fail "worker b regenerated nothing"
# The job is over: its batch directories are removed.
n=0
while ls "$TMP"/cb/batches/*/b* >/dev/null 2>&1; do
    n=$((n + 1))
    [ $n -lt 100 ] || { ls -R "$TMP/cb/batches"; fail "worker b kept the job's batch files"; }
    sleep 0.1
done
# Worker a, killed with its batch files, learns on its return that the job
# ended while it was away, and removes them.
ls -d "$TMP/ca/batches/$id"-* >/dev/null 2>&1 || fail "worker a's batch directory is gone already"
start_worker "$TMP/a2.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/ca" --name a
n=0
while ls -d "$TMP/ca/batches/$id"-* >/dev/null 2>&1; do
    n=$((n + 1))
    [ $n -lt 100 ] || { ls -R "$TMP/ca/batches"; fail "worker a kept the ended job's batch files"; }
    sleep 0.1
done

# The coordinator killed once a checkpoint holds part of the animation.
id=$("$GI" submit "$TMP/job.json" 2>"$TMP/submit.log") || { cat "$TMP/submit.log"; fail "submit 2"; }
wait_merged_tasks "$id" 30
wait_checkpoint "$id" 30
unended "$id" || fail "job $id ended before its checkpoint of 30 tasks"
kill -9 "$FARMD_PID"
wait "$FARMD_PID" 2>/dev/null || true
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$LOG" -- $OPTS $PORTS
wait_state "$id" done 300
"$GI" fetch "$id" --out "$TMP/restarted" >/dev/null || fail "fetch 2"
same_as_ref "$TMP/restarted" "coordinator restarted"

# A job that fails (frame 4's image cannot be written) keeps its batches on
# the workers; `gi retry` resumes it without tracing them again.
# (Its way blocked while no task can run, so before frame 4 is written.)
pools_stop
id=$("$GI" submit "$TMP/job.json" 2>"$TMP/submit.log") || { cat "$TMP/submit.log"; fail "submit 3"; }
mkdir "$TMP/state/jobs/$id/out/img.0004.exr"
pools_cont
wait_state "$id" failed 300
ls "$TMP"/ca/batches/"$id"-*/b* "$TMP"/cb/batches/"$id"-*/b* >/dev/null 2>&1 ||
    { ls -R "$TMP/ca/batches" "$TMP/cb/batches"; fail "the failed job's batch files are gone"; }
rmdir "$TMP/state/jobs/$id/out/img.0004.exr"
"$GI" retry "$id" --wait --out "$TMP/retried" --progress none >"$TMP/retry.log" 2>&1 ||
    { cat "$TMP/retry.log"; fail "gi retry of the failed animation"; }
same_as_ref "$TMP/retried" "failed and retried"
for r in "$TMP"/retried/report.000*.json; do
    n=$(sed -n 's/.*"frames_regenerated":[^0-9]*\([0-9]*\).*/\1/p' "$r")
    [ "$n" = 0 ] || fail "$(basename "$r"): $n frames regenerated after the retry"
done
stop_farmd "$LOG"
echo "animation on the farm identical to gi render after a worker kill ($regen frames regenerated) and a coordinator restart"
