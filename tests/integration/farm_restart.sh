# kill -9 of gi-farmd in the middle of a job, then a restart on the same
# state directory: the job resumes from its last checkpoint and completes
# with a byte-identical image; the tasks merged before that checkpoint are
# not run again (the new coordinator accepts exactly total - resumed
# results). Then the same after a clean stop (SIGTERM checkpoints at once),
# with the journal's record of that last checkpoint cut off as a crash
# between the file's rename and its record would: the newer file is
# resumed, under its own number.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
cornell_job "$TMP/job.json" 21 128 96 512
OPTS="--heartbeat 0.2 --lease 2 --dead 10 --checkpoint 0.2"
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$TMP/farmd.log" -- $OPTS
PORTS="--listen-workers $WADDR --listen-api $API"
start_worker "$TMP/worker.log" -- --connect "$WADDR" --procs 2 --cache "$TMP/cache"
id=$("$GI" submit "$TMP/job.json" 2>"$TMP/submit.log") || { cat "$TMP/submit.log"; fail "submit"; }

# A client waiting for the job all along: it waits out the restarts.
"$GI" wait "$id" --out "$TMP/waited" --progress none >"$TMP/wait.log" 2>&1 &
waiter=$!

# 1. kill -9 with at least a fifth merged and checkpointed.
wait_merged "$id" 5 checkpoint
seen=$merged
kill -9 "$FARMD_PID"
wait "$FARMD_PID" 2>/dev/null || true
sleep 1 # the waiter finds nobody for a while
echo "killed gi-farmd -9 with $seen of $total tasks in the last checkpoint seen"
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$TMP/farmd.log" -- $OPTS $PORTS
wait_state "$id" running 60
resumed=$(jnum "$id" resumed_merged)
[ "$resumed" -ge "$seen" ] || fail "resumed with $resumed merged, the checkpoint had $seen"
# Its progress counts what the checkpoint brought, not from 0.
progress=$(api "/api/v1/jobs/$id" | grep -o '"progress":[0-9.e-]*' | cut -d: -f2)
awk -v p="$progress" -v r="$resumed" -v t="$total" 'BEGIN { exit !(p > 0.5 * r / t) }' ||
    fail "restored at $resumed of $total tasks, the job says $progress done"

# 2. A clean stop later on: SIGTERM checkpoints everything merged so far.
wait_merged "$id" 2 checkpoint
stop_farmd "$TMP/farmd.log"
grep -q "stopping: checkpointing running jobs" "$TMP/farmd.log" || fail "no checkpoint on SIGTERM"
# The worker was told goodbye, not reset.
wait_log "$TMP/worker.log" "the coordinator said goodbye"
# The last record is the stop's CHECKPOINT (44 bytes: type, length, job id,
# seq, merged, tasks, CRC); its seq is at 16 bytes in.
J="$TMP/state/journal"
size=$(wc -c <"$J")
[ "$(od -An -tu4 -j $((size - 44)) -N 4 "$J" | tr -d ' ')" = 2 ] || fail "no CHECKPOINT at the end"
seq=$(od -An -tu8 -j $((size - 28)) -N 8 "$J" | tr -d ' ')
truncate -s $((size - 44)) "$J"
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$TMP/farmd.log" -- $OPTS $PORTS
wait_state "$id" done 120
resumed2=$(jnum "$id" resumed_merged)
results=$(jnum "$id" results_this_run)
total=$(jnum "$id" total)
[ "$resumed2" -gt "$resumed" ] || fail "the second restart resumed from $resumed2 <= $resumed"
# Not redone: this coordinator ran exactly the tasks the checkpoint lacked.
[ "$results" -eq $((total - resumed2)) ] ||
    fail "accepted $results results after resuming at $resumed2 of $total"
api "/api/v1/jobs/$id" | grep -q "taken as checkpoint $seq\".*resumed from checkpoint $seq:" ||
    { api "/api/v1/jobs/$id"; fail "the checkpoint file was not resumed as checkpoint $seq"; }
"$GI" fetch "$id" --out "$TMP/farm" >/dev/null || fail "fetch"
cmp "$TMP/job.json.ref/img.exr" "$TMP/farm/img.exr" || fail "the image differs after the restarts"
wait "$waiter" || { cat "$TMP/wait.log"; fail "gi wait gave up across the restarts"; }
grep -q "gi-farmd at .* does not answer" "$TMP/wait.log" && grep -q "the farm answers again" "$TMP/wait.log" ||
    { cat "$TMP/wait.log"; fail "gi wait did not say it waited for the farm"; }
cmp "$TMP/job.json.ref/img.exr" "$TMP/waited/img.exr" || fail "gi wait fetched another image"
# The journal's replay survives a torn tail (a crash in the middle of an append).
stop_farmd "$TMP/farmd.log"
printf '\003\000\000\000\377\377' >>"$TMP/state/journal"
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$TMP/farmd.log" -- $OPTS $PORTS
grep -q "journal: record at byte .* is torn" "$TMP/farmd.log" || fail "the torn record was not reported"
[ "$(jstate "$id")" = done ] || fail "the job is not remembered as done"
# ... with its run's numbers, not zeros.
[ "$(jnum "$id" total)" = "$total" ] && api "/api/v1/jobs/$id" | grep -q '"started":"' ||
    { api "/api/v1/jobs/$id"; fail "the restart forgot the done job's tasks or start"; }
stop_farmd "$TMP/farmd.log"
echo "identical; resumed at $resumed then $resumed2 of $total merged, $results results after the last restart"
