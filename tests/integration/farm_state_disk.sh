# The coordinator's own disk turns read-only (or full) under a running job:
# 1. the job's log lines written meanwhile (its failed checkpoint) reach its
#    log file once the disk takes writes again, whole, instead of being
#    lost; the job goes on and ends with the image `gi render` gives.
# 2. a job that ends on a full disk, where neither its outputs nor a
#    checkpoint of its result fit, waits in memory and writes them once
#    there is room, instead of failing (a retry would render again).
# 3. a job that ends while the journal refuses its END record (immutable
#    here, as a full disk would) keeps its checkpoint until the END is
#    journaled, at a later tick; a coordinator killed then knows it done.
# 4. a result waiting in memory as in 2 survives a stop of gi-farmd while
#    the disk is still full: it is written in the room of the job's
#    checkpoint before, and the coordinator restarted (with room again)
#    resumes with every task merged and writes the outputs, running no
#    task again. 5. without a checkpoint before, a restart runs it again.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
need_own_disk 16m
command -v nsenter >/dev/null 2>&1 || skip "nsenter (util-linux) is not installed"
touch "$TMP/probe.imm"
chattr +i "$TMP/probe.imm" 2>/dev/null && chattr -i "$TMP/probe.imm" ||
    skip "chattr +i does not work here"
make_secrets
cornell_job "$TMP/job.json" 5 64 64 512 8
mkdir -p "$TMP/state/jobs"
LOG="$TMP/farmd.log"
start_farmd "$TMP/state" "$LOG" sh "$TMP/own_disk.sh" "$TMP/state/jobs" -- \
    --heartbeat 0.2 --lease 5 --dead 20 --checkpoint 0.2
start_worker "$TMP/worker.log" -- --connect "$WADDR" --procs 2 --cache "$TMP/cache"
# The jobs directory as gi-farmd sees it (its mount namespace).
JOBS=/proc/$FARMD_PID/root$TMP/state/jobs
id=$("$GI" submit "$TMP/job.json" 2>"$TMP/submit.log") || { cat "$TMP/submit.log"; fail "submit"; }
wait_merged "$id" 4 checkpoint
nsenter -t "$FARMD_PID" -m mount -o remount,ro "$TMP/state/jobs" || fail "remount read-only"
wait_log "$LOG" "job $id: checkpoint failed (the job goes on): .*Read-only file system"
kill -STOP "$WORKER_PID" $(pgrep -P "$WORKER_PID") # the job waits while we look
! grep -q "checkpoint failed" "$JOBS/$id/log" || fail "a read-only disk took a log line"
nsenter -t "$FARMD_PID" -m mount -o remount,rw "$TMP/state/jobs" || fail "remount read-write"
# The line waiting in memory reaches the job's log once it has room.
wait_log "$JOBS/$id/log" "checkpoint failed (the job goes on): .*Read-only file system"
kill -CONT "$WORKER_PID" $(pgrep -P "$WORKER_PID")
wait_state "$id" done 120
grep -vq '^20[0-9][0-9]-[0-9][0-9]-[0-9][0-9]T' "$JOBS/$id/log" &&
    { cat "$JOBS/$id/log"; fail "a line of the job's log is cut"; }
grep -q "checkpoint [0-9]* written: checkpoints work again" "$JOBS/$id/log" ||
    { cat "$JOBS/$id/log"; fail "the log does not say checkpoints work again"; }
"$GI" fetch "$id" --out "$TMP/out" >/dev/null || fail "fetch"
cmp "$TMP/job.json.ref/img.exr" "$TMP/out/img.exr" || fail "the image differs from gi render"

# 2. A full disk at the job's end.
id=$("$GI" submit "$TMP/job.json" 2>"$TMP/submit.log") || fail "submit 2"
wait_merged "$id" 4 checkpoint
kill -STOP "$WORKER_PID" $(pgrep -P "$WORKER_PID")
dd if=/dev/zero of="$JOBS/fill" bs=64k 2>/dev/null && fail "16 MiB did not fill up"
kill -CONT "$WORKER_PID" $(pgrep -P "$WORKER_PID")
wait_log "$LOG" "job $id: its outputs cannot be written (.*No space left on device.*), nor"
# running, or finishing a retry of its outputs
unended "$id" || { api "/api/v1/jobs/$id"; fail "the job did not wait for room"; }
rm "$JOBS/fill"
wait_state "$id" done 60
api "/api/v1/jobs/$id" | grep -q "its outputs are written now" || fail "the log does not say so"
"$GI" fetch "$id" --out "$TMP/out2" >/dev/null || fail "fetch 2"
cmp "$TMP/job.json.ref/img.exr" "$TMP/out2/img.exr" || fail "job 2's image differs from gi render"
stop_farmd "$LOG"
kill -9 "$WORKER_PID"

# 3. The END of a job refused by the journal.
S2="$TMP/state2"
trap 'chattr -i "$S2/journal" 2>/dev/null; farm_cleanup' EXIT
OPTS="--heartbeat 0.2 --lease 5 --dead 20 --checkpoint 0.2"
# shellcheck disable=SC2086
start_farmd "$S2" "$LOG" -- $OPTS
PORTS="--listen-workers $WADDR --listen-api $API"
start_worker "$TMP/worker2.log" -- --connect "$WADDR" --procs 2 --cache "$TMP/cache"
id=$("$GI" submit "$TMP/job.json" 2>"$TMP/submit.log") || fail "submit 3"
wait_merged "$id" 4 checkpoint
chattr +i "$S2/journal"
wait_state "$id" done 120
[ -e "$S2/jobs/$id/checkpoint" ] || fail "a done job whose end is not journaled lost its checkpoint"
api "/api/v1/jobs/$id" | grep -q "its end cannot be journaled" || fail "the log does not say so"
chattr -i "$S2/journal"
wait_log "$LOG" "job $id: its end is journaled now"
[ ! -e "$S2/jobs/$id/checkpoint" ] || fail "the checkpoint stayed once the end was journaled"
kill -9 "$FARMD_PID"
wait "$FARMD_PID" 2>/dev/null || true
# shellcheck disable=SC2086
start_farmd "$S2" "$LOG" -- $OPTS $PORTS
[ "$(jstate "$id")" = done ] || { api "/api/v1/jobs/$id"; fail "the restart forgot the job's end"; }
"$GI" fetch "$id" --out "$TMP/out3" >/dev/null || fail "fetch 3"
cmp "$TMP/job.json.ref/img.exr" "$TMP/out3/img.exr" || fail "job 3's image differs from gi render"
stop_farmd "$LOG"
kill -9 "$WORKER_PID" # step 4's worker takes its cache (one gi-worker per cache)

# 4. A held result across a restart: the disk (a tmpfs) outlives gi-farmd in
# a mount namespace a sleeping process keeps.
S4="$TMP/state4"
mkdir -p "$S4/jobs"
unshare -m sh -c 'mount -t tmpfs -o size=16m tmpfs "$0" && exec sleep 600' "$S4/jobs" &
HOLDER=$!
FARM_PIDS="$FARM_PIDS $HOLDER"
JOBS4=/proc/$HOLDER/root$S4/jobs
n=0
until [ "$(stat -f -c %T "$JOBS4" 2>/dev/null)" = tmpfs ]; do
    n=$((n + 1))
    [ $n -lt 200 ] || fail "no tmpfs for step 4"
    sleep 0.05
done
# shellcheck disable=SC2086
start_farmd "$S4" "$LOG" nsenter -t "$HOLDER" -m -- $OPTS
PORTS="--listen-workers $WADDR --listen-api $API"
start_worker "$TMP/worker4.log" -- --connect "$WADDR" --procs 2 --cache "$TMP/cache"
id=$("$GI" submit "$TMP/job.json" 2>"$TMP/submit.log") || fail "submit 4"
# The image's way is blocked too, so that the room the kept result leaves
# does not let the outputs through before gi-farmd stops.
mkdir -p "$JOBS4/$id/out/img.exr"
wait_merged "$id" 4 checkpoint
kill -STOP "$WORKER_PID" $(pgrep -P "$WORKER_PID")
dd if=/dev/zero of="$JOBS4/fill" bs=64k 2>/dev/null && fail "16 MiB did not fill up (4)"
kill -CONT "$WORKER_PID" $(pgrep -P "$WORKER_PID")
wait_log "$LOG" "job $id: its outputs cannot be written (.*img.exr: .*), nor"
total=$(jnum "$id" total)
[ "$(jckpt "$id" merged)" = "$total" ] || { api "/api/v1/jobs/$id"; fail "the held result is not in the checkpoint"; }
unended "$id" || { api "/api/v1/jobs/$id"; fail "the job did not wait for room"; }
stop_farmd "$LOG"
kill -9 "$WORKER_PID"
rm "$JOBS4/fill"
rmdir "$JOBS4/$id/out/img.exr"
# shellcheck disable=SC2086
start_farmd "$S4" "$LOG" nsenter -t "$HOLDER" -m -- $OPTS $PORTS
start_worker "$TMP/worker4b.log" -- --connect "$WADDR" --procs 2 --cache "$TMP/cache"
wait_state "$id" done 60
[ "$(jnum "$id" resumed_merged)" = "$total" ] && [ "$(jnum "$id" results_this_run)" = 0 ] ||
    { api "/api/v1/jobs/$id"; fail "the restart ran tasks of the held result again"; }
"$GI" fetch "$id" --out "$TMP/out4" >/dev/null || fail "fetch 4"
cmp "$TMP/job.json.ref/img.exr" "$TMP/out4/img.exr" || fail "job 4's image differs from gi render"
grep -q "job $id: its outputs cannot be written (.*), nor .*; the result is kept in checkpoint [0-9]*, written in the room of the one before: a restart resumes from it" "$LOG" ||
    fail "the log does not say where the held result is kept"
stop_farmd "$LOG"

# 5. With no checkpoint before to give its room (none is taken in time), the
# held result cannot be kept on disk: the log says a restart runs the job
# again from the start, and one does (it is still running in the journal).
# shellcheck disable=SC2086
start_farmd "$S4" "$LOG" nsenter -t "$HOLDER" -m -- $OPTS $PORTS --checkpoint 1000
id=$("$GI" submit "$TMP/job.json" 2>"$TMP/submit.log") || fail "submit 5"
mkdir -p "$JOBS4/$id/out/img.exr"
wait_merged "$id" 4
kill -STOP "$WORKER_PID" $(pgrep -P "$WORKER_PID")
dd if=/dev/zero of="$JOBS4/fill" bs=64k 2>/dev/null && fail "16 MiB did not fill up (5)"
kill -CONT "$WORKER_PID" $(pgrep -P "$WORKER_PID")
wait_log "$LOG" "job $id: its outputs cannot be written (.*img.exr: .*), nor .*; a restart would run it again from the start"
stop_farmd "$LOG"
rm "$JOBS4/fill"
rmdir "$JOBS4/$id/out/img.exr"
# shellcheck disable=SC2086
start_farmd "$S4" "$LOG" nsenter -t "$HOLDER" -m -- $OPTS $PORTS
wait_state "$id" done 120
"$GI" fetch "$id" --out "$TMP/out5" >/dev/null || fail "fetch 5"
cmp "$TMP/job.json.ref/img.exr" "$TMP/out5/img.exr" || fail "job 5's image differs from gi render"
stop_farmd "$LOG"
kill "$HOLDER"
echo ok
