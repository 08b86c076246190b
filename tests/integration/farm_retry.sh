# `gi retry`: a failed or a cancelled farm job runs again from its last
# checkpoint and ends with the image an uninterrupted render gives.
# 1. A job whose output cannot be written (a directory in the way of
#    img.exr, as a full disk would be) fails at its end with its whole
#    result in a checkpoint; a retry while the way is still blocked fails
#    again and keeps it; after a restart of gi-farmd (the journal keeps the
#    checkpoint), and once the way is clear, `gi retry --wait` writes the
#    image without running a task again and fetches it.
# 2. A job cancelled halfway, retried: the same.
# 3. Refusals: a job that is done (409), one that does not exist (404).
# 4. A checkpoint that cannot be written: said once, the job goes on.
# 5. A detp animation whose frame's image cannot be written keeps all it
#    rendered; its retry renders only the frames after.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
cornell_job "$TMP/job.json" 31 128 96 512
OPTS="--heartbeat 0.2 --lease 2 --dead 10 --checkpoint 0.2"
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$TMP/farmd.log" -- $OPTS
PORTS="--listen-workers $WADDR --listen-api $API"

# 1. Failed on its output. (Its way blocked before a worker is there: no
# task runs before the directory is in place, however busy the machine.)
id=$("$GI" submit "$TMP/job.json" 2>"$TMP/submit.log") || { cat "$TMP/submit.log"; fail "submit"; }
mkdir "$TMP/state/jobs/$id/out/img.exr"
start_worker "$TMP/worker.log" -- --connect "$WADDR" --procs 2 --cache "$TMP/cache"
wait_state "$id" failed 120
api "/api/v1/jobs/$id" | grep -q 'img.exr: rename' || { api "/api/v1/jobs/$id"; fail "no reason"; }
seen=$(jckpt "$id" merged)
[ "${seen:-0}" -gt 0 ] && [ "$seen" = "$(jnum "$id" total)" ] ||
    { api "/api/v1/jobs/$id"; fail "the failed job's checkpoint lacks part of its result"; }
st=0
"$GI" wait "$id" --out "$TMP/none" --progress none >"$TMP/wait1.log" 2>&1 || st=$?
kept="the whole result is kept in checkpoint [0-9]*: a retry only writes the outputs"
hint="gi retry $id. runs it again from its last checkpoint ($seen of $seen tasks merged)"
[ $st -eq 1 ] && grep -q "job $id failed: .*img.exr: rename.*$kept; .$hint" "$TMP/wait1.log" ||
    { cat "$TMP/wait1.log"; fail "gi wait on the failed job: exit $st, no retry hint"; }
st=0
"$GI" retry "$id" --wait --out "$TMP/none" --progress none >"$TMP/retry0.log" 2>&1 || st=$?
[ $st -eq 1 ] && grep -q "img.exr: rename.*$kept; .$hint" "$TMP/retry0.log" ||
    { cat "$TMP/retry0.log"; fail "a retry with the way still blocked: exit $st"; }
[ "$(jckpt "$id" merged)" = "$seen" ] && [ "$(jnum "$id" results_this_run)" = 0 ] ||
    { api "/api/v1/jobs/$id"; fail "a retry with the way still blocked lost the result"; }
stop_farmd "$TMP/farmd.log"
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$TMP/farmd.log" -- $OPTS $PORTS
[ "$(jstate "$id")" = failed ] || fail "the job is not remembered as failed"
[ "$(jckpt "$id" merged)" = "$seen" ] || fail "the restart forgot the failed job's checkpoint"
rmdir "$TMP/state/jobs/$id/out/img.exr"
"$GI" retry "$id" --wait --out "$TMP/failed" --progress none >"$TMP/retry1.log" 2>&1 ||
    { cat "$TMP/retry1.log"; fail "gi retry --wait of the failed job"; }
grep -q "job $id runs again" "$TMP/retry1.log" || fail "gi retry did not say so"
resumed=$(jnum "$id" resumed_merged)
results=$(jnum "$id" results_this_run)
total=$(jnum "$id" total)
[ "$resumed" -ge "$seen" ] || fail "the retry resumed at $resumed, the checkpoint had $seen"
[ "$results" -eq 0 ] && [ "$resumed" -eq "$total" ] || fail "the retry ran $results tasks, not 0"
api "/api/v1/jobs/$id" | grep -q "retried after it failed (.*img.exr: rename" || fail "no retry in the job's log"
cmp "$TMP/job.json.ref/img.exr" "$TMP/failed/img.exr" || fail "the retried job's image differs"

# 2. Cancelled halfway.
id2=$("$GI" submit "$TMP/job.json" 2>"$TMP/submit2.log") || { cat "$TMP/submit2.log"; fail "submit 2"; }
wait_merged "$id2" 3 checkpoint
seen2=$merged
"$GI" cancel "$id2" >/dev/null || fail "cancel"
wait_state "$id2" cancelled 10
"$GI" retry "$id2" --wait --out "$TMP/cancelled" --progress none >"$TMP/retry2.log" 2>&1 ||
    { cat "$TMP/retry2.log"; fail "gi retry --wait of the cancelled job"; }
[ "$(jnum "$id2" resumed_merged)" -ge "$seen2" ] || fail "the cancelled job did not resume"
api "/api/v1/jobs/$id2" | grep -q "retried after it was cancelled" || fail "no retry in job 2's log"
cmp "$TMP/job.json.ref/img.exr" "$TMP/cancelled/img.exr" || fail "the retried cancelled job differs"

# 3. Refusals.
st=0
"$GI" retry "$id" >"$TMP/retry3.log" 2>&1 || st=$?
[ $st -eq 1 ] && grep -q "is done: only a failed or cancelled job is retried (HTTP 409)" "$TMP/retry3.log" ||
    { cat "$TMP/retry3.log"; fail "retrying a done job: exit $st"; }
st=0
"$GI" retry 999 >"$TMP/retry4.log" 2>&1 || st=$?
[ $st -eq 1 ] && grep -q "no job 999 (HTTP 404 from the farm at" "$TMP/retry4.log" ||
    { cat "$TMP/retry4.log"; fail "retrying a missing job: exit $st"; }
[ "$(api "/api/v1/jobs/$id/retry" -o /dev/null -w '%{http_code}')" = 405 ] || fail "GET .../retry"
[ "$(metric gi_farm_jobs_retried_total)" = 2 ] || fail "retries counted: $(metric gi_farm_jobs_retried_total)"

# 4. Checkpoints that cannot be written (a directory in the way of the
# file) are said in the job's log and view, once; the job goes on. (The
# way blocked while no task runs: before the job can merge and checkpoint.)
pools_stop
id3=$("$GI" submit "$TMP/job.json" 2>"$TMP/submit3.log") || { cat "$TMP/submit3.log"; fail "submit 3"; }
mkdir "$TMP/state/jobs/$id3/checkpoint"
pools_cont
wait_state "$id3" done 120
view=$(api "/api/v1/jobs/$id3")
echo "$view" | grep -q '"last_error":"[^"]*checkpoint[^"]*"' || { echo "$view"; fail "no checkpoint error in the view"; }
[ "$(echo "$view" | grep -o 'checkpoint failed (the job goes on)' | wc -l)" = 1 ] ||
    { echo "$view"; fail "the checkpoint failure is not in the job's log once"; }
[ "$(metric gi_farm_checkpoint_failures_total)" -ge 1 ] || fail "checkpoint failures not counted"

# 5. A detp animation whose frame 2 image cannot be written fails at the end
# of frame 3 (frame 2's image is written while frame 3 runs) with all it
# rendered in its checkpoint: frame 2's image and frame 3, whole. Its retry
# writes them and renders frames 4 on, nothing before again, and ends with
# the frames `gi render` gives.
write_job "$TMP/anim.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene-mobile.json", "method": "detp", "seed": 11,
 "image": {"width": 32, "height": 32},
 "detp": {"photons": 400000, "batch": 50000, "subdivide": 40, "tile": 16, "image_spp": 1,
          "animation": {"object": "mobile", "frames": 6,
                        "keyframes": [{"frame": 0, "translate": [340, -338.9, -90]},
                                      {"frame": 5, "translate": [248, -338.9, -0.4]}]}},
 "outputs": {"exr": "img.exr", "bin": "v.bin", "json": "report.json"}}
JOB
"$GI_RELEASE" render "$TMP/anim.json" --workers 2 --out "$TMP/anim-ref" --progress none \
    >"$TMP/anim-ref.log" 2>&1 || { cat "$TMP/anim-ref.log"; fail "gi render of the animation"; }
id5=$("$GI" submit "$TMP/anim.json" 2>"$TMP/submit5.log") || { cat "$TMP/submit5.log"; fail "submit 5"; }
OUT5="$TMP/state/jobs/$id5/out"
mkdir -p "$OUT5/img.0002.exr"
wait_state "$id5" failed 120
api "/api/v1/jobs/$id5" | grep -q "img.0002.exr: rename.*frames rendered so far are kept in checkpoint" ||
    { api "/api/v1/jobs/$id5"; fail "the animation did not keep its frames"; }
seen5=$(jckpt "$id5" merged)
[ "$seen5" = "$(jnum "$id5" total)" ] || { api "/api/v1/jobs/$id5"; fail "frame 3 not whole in the checkpoint"; }
[ -e "$OUT5/v.0002.bin" ] && [ ! -e "$OUT5/v.0003.bin" ] || fail "frame 2's or 3's outputs"
touch -d '1 minute ago' "$OUT5"/*.0*
touch -d '30 seconds ago' "$TMP/before-retry5"
rmdir "$OUT5/img.0002.exr"
"$GI" retry "$id5" --wait --out "$TMP/anim-out" --progress none >"$TMP/retry5.log" 2>&1 ||
    { cat "$TMP/retry5.log"; fail "gi retry --wait of the animation"; }
[ "$(jnum "$id5" resumed_merged)" = "$seen5" ] || fail "the animation's retry did not resume at $seen5"
written=$(cd "$OUT5" && find . -name '*.000[0-3].*' -newer "$TMP/before-retry5" | sort | tr '\n' ' ')
[ "$written" = "./img.0002.exr ./img.0003.exr ./report.0003.json ./v.0003.bin " ] ||
    fail "the retry wrote again $written"
for f in 0000 0001 0002 0003 0004 0005; do
    for k in img.$f.exr v.$f.bin; do
        cmp "$TMP/anim-ref/$k" "$TMP/anim-out/$k" || fail "the retried animation's $k differs"
    done
done
stop_farmd "$TMP/farmd.log"
echo "failed job retried after a restart from $resumed of $total tasks, cancelled one from $seen2: identical"
