# A job's finish (writing its outputs) runs on a thread of gi-farmd's, not
# on its loop; GI_FAULT_FINISH_GATE holds each finish there until the test
# lets it through (release), whatever the machine's load.
# 1. Meanwhile the job shows as "finishing" (its view, `gi status`, the
#    metrics), its outputs are not served yet, and the API answers; then it
#    is done with the image `gi render` gives, and the loop's longest round
#    is in the metrics; `gi wait` then says it was done already (no rate).
# 2. An output that cannot be written while the thread writes (a directory
#    in the way): the job fails with its whole result in a checkpoint, and a
#    retry once the way is clear writes the outputs without running a task.
# 3. Cancelled while finishing: the cancel answers at once, the job
#    "cancelling" at 99.9% (not 100%: it will not be done) while its finish
#    runs (its log says why), its END journaled then; a second cancel
#    and a purge are refused meanwhile; the loop does not wait for the
#    finish (its longest round stays under 1.5 s, the finish held longer). Once the
#    finish has returned the job is cancelled, its outputs not served, with
#    no second END; a retry ends done, with the same image.
# 3b. gi-farmd killed between such a cancel and the finish's return: the
#    restarted one has the job cancelled.
# 4. gi-farmd stopped (SIGTERM) while a job finishes: it waits for the
#    finish (still running while the finish is held) and journals the job
#    done; restarted, it serves the outputs.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
cornell_job "$TMP/job.json" 7 64 48 64
LOG="$TMP/farmd.log"
OPTS="--heartbeat 0.2 --lease 5 --dead 20 --checkpoint 0.2"
# shellcheck disable=SC2086
GATE="$TMP/finish-gate"
start_farmd "$TMP/state" "$LOG" env GI_FAULT_FINISH_GATE="$GATE" -- $OPTS
PORTS="--listen-workers $WADDR --listen-api $API"
start_worker "$TMP/worker.log" -- --connect "$WADDR" --procs 2 --cache "$TMP/cache"
# Lets one finish through (the finish removes the file: the one before
# must have been taken).
release() {
    [ ! -e "$GATE" ] || fail "a finish was let through and none took it"
    : >"$GATE"
}
submit() {
    "$GI" submit "$TMP/job.json" 2>"$TMP/submit.log" || { cat "$TMP/submit.log"; fail "submit"; }
}

# 1. Finishing, then done.
id=$(submit)
wait_state "$id" finishing 120
[ "$(metric gi_farm_jobs_finishing)" = 1 ] || { api /metrics; fail "no finishing job in the metrics"; }
"$GI" status "$id" | grep -q "^job $id: .*, finishing, " || { "$GI" status "$id"; fail "gi status"; }
code=$(api "/api/v1/jobs/$id/outputs/img.exr" -o /dev/null -w '%{http_code}')
[ "$code" = 409 ] || fail "an output of a finishing job was answered $code"
[ "$(jnum "$id" merged)" = "$(jnum "$id" total)" ] || fail "finishing before every task merged"
sleep 1
[ "$(jstate "$id")" = finishing ] || fail "the held finish ended: $(jstate "$id")"
release
wait_state "$id" done 60
"$GI" fetch "$id" --out "$TMP/o1" >/dev/null || fail "fetch 1"
cmp "$TMP/job.json.ref/img.exr" "$TMP/o1/img.exr" || fail "the image differs from gi render"
# gi wait on a job done before it: the summary, saying so, and no rate (over no time: 0/s).
"$GI" wait "$id" --out "$TMP/o1w" --progress lines >"$TMP/wait1.out" 2>"$TMP/wait1.err" ||
    { cat "$TMP/wait1.out" "$TMP/wait1.err"; fail "gi wait of a done job"; }
grep -q "^[^ ]*: job $id (pt) done on the farm already, at 20" "$TMP/wait1.out" &&
    ! grep -q "/s" "$TMP/wait1.out" "$TMP/wait1.err" && cmp "$TMP/o1/img.exr" "$TMP/o1w/img.exr" ||
    { cat "$TMP/wait1.out" "$TMP/wait1.err"; fail "gi wait of a done job: what it says"; }
# An ended job has no ETA (not "0.0s") in gi jobs and gi status.
"$GI" jobs | grep -Eq "^$id +done +[0-9]+ +100\.0% +pt " && "$GI" status "$id" >"$TMP/st1" &&
    grep -q "^  progress 100.0%$" "$TMP/st1" || { "$GI" jobs; cat "$TMP/st1"; fail "a done job's ETA"; }
[ "$(metric gi_farm_jobs_finishing)" = 0 ] || fail "still a finishing job in the metrics"
stall=$(metric gi_farm_loop_stall_max_seconds)
awk -v s="$stall" 'BEGIN {exit !(s > 0)}' || fail "no loop stall metric ($stall)"

# 2. The output cannot be written while the thread writes it.
id=$(submit)
wait_state "$id" finishing 120
mkdir -p "$TMP/state/jobs/$id/out/img.exr"
release
wait_state "$id" failed 60
api "/api/v1/jobs/$id" |
    grep -q 'img.exr: rename.*the whole result is kept in checkpoint [0-9]*: a retry only writes' ||
    { api "/api/v1/jobs/$id"; fail "no reason, or the result was not kept"; }
[ "$(jckpt "$id" merged)" = "$(jnum "$id" total)" ] || fail "the checkpoint lacks part of the result"
rmdir "$TMP/state/jobs/$id/out/img.exr"
release # for the retry's finish
"$GI" retry "$id" --wait --out "$TMP/o2" --progress none >"$TMP/retry2.log" 2>&1 ||
    { cat "$TMP/retry2.log"; fail "gi retry --wait"; }
[ "$(jnum "$id" results_this_run)" = 0 ] || fail "the retry ran tasks again"
cmp "$TMP/job.json.ref/img.exr" "$TMP/o2/img.exr" || fail "the retried image differs"

# 3. Cancelled while finishing.
ends() { # the END records of the jobs cancelled through the API
    grep -a -o "cancelled: requested through the API" "$TMP/state/journal" | wc -l
}
id=$(submit)
wait_state "$id" finishing 120
e0=$(ends)
"$GI" cancel "$id" >"$TMP/cancel.out" || fail "gi cancel of a finishing job"
grep -q "cancelled: it ends once the outputs being written are" "$TMP/cancel.out" ||
    { cat "$TMP/cancel.out"; fail "gi cancel does not say the job ends later"; }
[ "$(jstate "$id")" = cancelling ] || fail "the cancel waited for the finish: $(jstate "$id")"
# Neither about to be done nor done: cancelling, then cancelled, at 99.9%, never 100%.
jobs_row() {
    "$GI" jobs >"$TMP/jobs.txt" || fail "gi jobs"
    grep -Eq "^$id +$1 +[0-9]+ +99\.9% " "$TMP/jobs.txt" ||
        { cat "$TMP/jobs.txt"; fail "gi jobs does not show job $id $1 at 99.9%"; }
}
jobs_row cancelling
[ "$(metric gi_farm_jobs_finishing)" = 1 ] || fail "the cancelling job's finish is not counted"
api "/api/v1/jobs/$id" | grep -q "the cancel waits for the outputs being written" ||
    { api "/api/v1/jobs/$id"; fail "the job's log does not say the cancel waits"; }
[ $(($(ends))) = $((e0 + 1)) ] || fail "the cancel's END is not journaled at once"
code=$(api "/api/v1/jobs/$id" -X DELETE -o "$TMP/cancel2.json" -w '%{http_code}')
[ "$code" = 409 ] && grep -q "cancelled already" "$TMP/cancel2.json" ||
    { cat "$TMP/cancel2.json"; fail "a second cancel was answered $code"; }
code=$(api "/api/v1/jobs/$id?purge=1" -X DELETE -o "$TMP/purge.json" -w '%{http_code}')
[ "$code" = 409 ] && grep -q "still being written" "$TMP/purge.json" ||
    { cat "$TMP/purge.json"; fail "a purge of the cancelling job was answered $code"; }
release
wait_state "$id" cancelled 60
jobs_row cancelled
code=$(api "/api/v1/jobs/$id/outputs/img.exr" -o /dev/null -w '%{http_code}')
[ "$code" = 409 ] || fail "an output of the cancelled job was answered $code"
[ $(($(ends))) = $((e0 + 1)) ] || fail "the END of the cancelled job is journaled twice"
stall=$(metric gi_farm_loop_stall_max_seconds)
echo "the loop's longest round so far: $stall s"
awk -v s="$stall" 'BEGIN {exit !(s < 1.5)}' || fail "the loop stalled for $stall s"
release
"$GI" retry "$id" --wait --out "$TMP/o3" --progress none >"$TMP/retry3.log" 2>&1 ||
    { cat "$TMP/retry3.log"; fail "gi retry --wait of the cancelled job"; }
cmp "$TMP/job.json.ref/img.exr" "$TMP/o3/img.exr" || fail "the image after cancel + retry differs"

# 3b. Killed between the cancel and the finish's return.
id=$(submit)
wait_state "$id" finishing 120
"$GI" cancel "$id" >/dev/null || fail "gi cancel of a finishing job (3b)"
kill -KILL "$FARMD_PID"
wait "$FARMD_PID" 2>/dev/null || true
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$LOG" env GI_FAULT_FINISH_GATE="$GATE" -- $OPTS $PORTS
[ "$(jstate "$id")" = cancelled ] || fail "job $id is $(jstate "$id") after the restart"
jobs_row cancelled

# 4. Stopped while finishing.
id=$(submit)
wait_state "$id" finishing 120
kill -TERM "$FARMD_PID"
sleep 1
kill -0 "$FARMD_PID" 2>/dev/null || fail "gi-farmd did not wait for the held finish"
! grep -q " done: " "$TMP/state/jobs/$id/log" || fail "the job is done, its finish held"
release
farmd_stopped "$LOG"
grep -q " done: " "$TMP/state/jobs/$id/log" ||
    { cat "$TMP/state/jobs/$id/log"; fail "the stop did not wait for the finish"; }
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$LOG" -- $OPTS $PORTS
[ "$(jstate "$id")" = done ] || fail "job $id is $(jstate "$id") after the restart, not done"
"$GI" fetch "$id" --out "$TMP/o4" >/dev/null || fail "fetch 4"
cmp "$TMP/job.json.ref/img.exr" "$TMP/o4/img.exr" || fail "the image after the stop differs"
stop_farmd "$LOG"
[ ! -e "$GATE" ] || fail "a finish was let through and none took it"
