# A damaged journal must not make new jobs adopt old ones' files. Job 1 is
# done, job 2 stopped with a checkpoint. A flipped byte in the journal's
# first record loses that record only (bit rot, not a torn tail). A damaged
# length there cuts the whole journal: the new job then gets an id past the
# job directories left (3, not 1), lists only its own outputs, and a
# checkpoint of another job put in its directory (same method and task
# counts) is refused: it starts over and its image is that of `gi render`.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
cornell_job "$TMP/a.json" 1 32 32 16
cornell_job "$TMP/b.json" 5 64 48 1024
cornell_job "$TMP/c.json" 9 64 48 1024
sed -i 's/img.exr/old-a.exr/' "$TMP/a.json"
sed -i 's/img.exr/old-b.exr/' "$TMP/b.json"
OPTS="--heartbeat 0.2 --lease 2 --dead 10 --checkpoint 0.2"
S=$TMP/state
# shellcheck disable=SC2086
start_farmd "$S" "$TMP/farmd.log" -- $OPTS
PORTS="--listen-workers $WADDR --listen-api $API"
start_worker "$TMP/worker.log" -- --connect "$WADDR" --procs 2 --cache "$TMP/cache"
"$GI" submit "$TMP/a.json" --wait --out "$TMP/a" --progress none >/dev/null 2>&1 || fail "job a"
id=$("$GI" submit "$TMP/b.json" 2>"$TMP/submit.log") || { cat "$TMP/submit.log"; fail "submit b"; }
[ "$id" = 2 ] || fail "job b got id $id"
wait_merged 2 5 checkpoint
kill -TERM "$WORKER_PID"
wait "$WORKER_PID" || true
stop_farmd "$TMP/farmd.log"
[ -f "$S/jobs/2/checkpoint" ] && [ -f "$S/jobs/1/out/old-a.exr" ] || fail "no old files to adopt"

# 1. Bit rot in the first record (job 1's SUBMIT): that record alone is lost.
flip() { # flip OFFSET MASK: the journal's byte at OFFSET XOR MASK
    b=$(od -An -tu1 -j "$1" -N 1 "$S/journal" | tr -d ' ')
    printf "\\$(printf %03o $((b ^ $2)))" |
        dd of="$S/journal" bs=1 seek="$1" conv=notrunc 2>/dev/null
}
flip 30 1
# shellcheck disable=SC2086
start_farmd "$S" "$TMP/farmd.log" -- $OPTS $PORTS
grep -q "record at byte 8 (type 1, SUBMIT) fails its CRC: skipped" "$TMP/farmd.log" ||
    fail "the damaged first record was not skipped"
wait_state 2 running 60
api /api/v1/jobs/1 | grep -q '"error"' || fail "job 1 is still known"
stop_farmd "$TMP/farmd.log"

# 2. The first record's length damaged: the whole journal is a torn tail.
flip 15 64
: >"$TMP/farmd2.log"
# shellcheck disable=SC2086
start_farmd "$S" "$TMP/farmd2.log" -- $OPTS $PORTS
grep -q "record at byte 8 is torn or damaged" "$TMP/farmd2.log" || fail "the cut was not reported"
grep -q "2 job directories the journal does not know" "$TMP/farmd2.log" ||
    fail "the job directories left were not reported"
[ "$(ls "$S"/journal.damaged-* | wc -l)" = 2 ] || fail "a damaged journal's copy was lost"
id=$("$GI" submit "$TMP/c.json" 2>"$TMP/submit.log") || { cat "$TMP/submit.log"; fail "submit c"; }
[ "$id" = 3 ] || fail "the new job got id $id, the id of a job directory left"
wait_state 3 running 60
stop_farmd "$TMP/farmd2.log"
# Another job's checkpoint in its directory, as an old job's would have been.
cp "$S/jobs/2/checkpoint" "$S/jobs/3/checkpoint"
# shellcheck disable=SC2086
start_farmd "$S" "$TMP/farmd2.log" -- $OPTS $PORTS
start_worker "$TMP/worker.log" -- --connect "$WADDR" --procs 2 --cache "$TMP/cache"
wait_state 3 done 120
grep -q "job 3: checkpoint unusable, starting over: .*a checkpoint of another job" \
    "$TMP/farmd2.log" || fail "the other job's checkpoint was not refused"
[ "$(jnum 3 resumed_merged)" = 0 ] || fail "job 3 resumed another job's checkpoint"
outputs=$(api /api/v1/jobs/3 | grep -o '"outputs":\[[^]]*\]')
echo "$outputs" | grep -q img.exr && ! echo "$outputs" | grep -q old- ||
    fail "job 3 lists other outputs: $outputs"
"$GI" fetch 3 --out "$TMP/c" >/dev/null || fail "fetch"
cmp "$TMP/c.json.ref/img.exr" "$TMP/c/img.exr" || fail "job 3's image is not its own"
stop_farmd "$TMP/farmd2.log"
echo "a damaged journal: one record skipped; cut, new ids skip the job directories left"
