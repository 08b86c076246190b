# Farm commands against a gi-farmd that is not running (docs/farm.md, "gi
# (client)"): they say at once on stderr that gi-farmd at the URL cannot be
# reached, where the URL came from ($GI_FARM, --farm) and how long they ask
# again (--retry S); then exit 1 saying to start gi-farmd or check the URL.
# A gi-farmd started within that time is still found (a restart is waited
# for), and gi wait gives up on a farm it never reached as the others do.
# gi wait says when a job waits for want of a worker. A farm reached that
# refuses the token is named too; so does a gi-worker
# started before gi-farmd, or pointed at its API port, and a second
# gi-farmd on a port in use.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
LOG="$TMP/farmd.log"
start_farmd "$TMP/state" "$LOG"
PORTS="--listen-workers $WADDR --listen-api $API"
stop_farmd "$LOG" # its port is closed now: "connection refused"

# --retry 0: one try, one line, exit 1.
rc=0
"$GI" jobs --retry 0 >"$TMP/jobs.out" 2>"$TMP/jobs.err" || rc=$?
[ $rc = 1 ] || fail "gi jobs against no farm: exit $rc"
grep -q "^gi: gi-farmd at http://$API (from \$GI_FARM) cannot be reached (cannot connect to $API: \
Connection refused): is it running? Start it (gi-farmd --state DIR" "$TMP/jobs.err" &&
    [ "$(wc -l <"$TMP/jobs.err")" = 1 ] && [ ! -s "$TMP/jobs.out" ] ||
    { cat "$TMP/jobs.out" "$TMP/jobs.err"; fail "gi jobs --retry 0: what it says"; }

# --farm: named as the URL's source; asked again for --retry S, said first.
rc=0
"$GI" status 1 --farm "http://$API" --retry 1 2>"$TMP/status.err" || rc=$?
[ $rc = 1 ] || fail "gi status against no farm: exit $rc"
head -n 1 "$TMP/status.err" | grep -q "^gi: gi-farmd at http://$API (from --farm) cannot be \
reached: cannot connect to $API: Connection refused; asking again for up to 1 s, in case it is \
restarting (--retry S: how long)$" &&
    tail -n 1 "$TMP/status.err" | grep -q "(from --farm) cannot be reached (.*), asked again for \
1 s: is it running?" || { cat "$TMP/status.err"; fail "gi status --retry 1: what it says"; }

# gi wait never answered: the same, not "the job goes on there".
rc=0
"$GI" wait 1 --retry 1 --progress none 2>"$TMP/wait.err" || rc=$?
[ $rc = 1 ] && grep -q "cannot be reached (.*), asked again for 1 s: is it running?" \
    "$TMP/wait.err" && ! grep -q "goes on there" "$TMP/wait.err" ||
    { cat "$TMP/wait.err"; fail "gi wait against no farm (exit $rc)"; }

# A gi-worker started before gi-farmd says once why it waits, and goes on asking.
timeout 3 "$WORKER" --connect "$WADDR" --procs 1 --cache "$TMP/wcache" >"$TMP/early.log" 2>&1 ||
    true
[ "$(grep -c "Connection refused (no gi-farmd listening for workers there yet: is it running, \
with --listen-workers $WADDR? asking again" "$TMP/early.log")" = 1 ] &&
    [ "$(grep -c "cannot connect to $WADDR: Connection refused$" "$TMP/early.log")" -ge 1 ] ||
    { cat "$TMP/early.log"; fail "gi-worker started before gi-farmd: what it says"; }
# Told by the connect's errno, not by words in the message: an address that
# cannot be resolved, whose name holds those words, gets no such hint.
timeout 3 "$WORKER" --connect "Connection refused:1" --procs 1 --cache "$TMP/wcache" \
    >"$TMP/words.log" 2>&1 || true
grep -q 'address "Connection refused:1": ' "$TMP/words.log" &&
    ! grep -q "no gi-farmd listening" "$TMP/words.log" ||
    { cat "$TMP/words.log"; fail "gi-worker took words in an address for a refused connection"; }

# Said at once, before the retries end; a gi-farmd started meanwhile answers.
"$GI" jobs --retry 60 >"$TMP/jobs2.out" 2>"$TMP/jobs2.err" &
client=$!
n=0
until grep -q "cannot be reached: .*asking again for up to 60 s" "$TMP/jobs2.err"; do
    n=$((n + 1)); [ $n -lt 100 ] || { cat "$TMP/jobs2.err"; fail "gi jobs did not say it at once"; }
    sleep 0.1
done
kill -0 "$client" || fail "gi jobs gave up at once"
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$LOG" -- $PORTS
wait "$client" || { cat "$TMP/jobs2.err"; fail "gi jobs did not find the farm started meanwhile"; }
grep -q "^ID .*STATE" "$TMP/jobs2.out" || { cat "$TMP/jobs2.out"; fail "gi jobs output"; }

# A farm with no worker: gi wait says why the job does not move, then it does.
cornell_job "$TMP/job.json" 3 16 16 8
id=$("$GI" submit "$TMP/job.json" 2>/dev/null) || fail "submit"
"$GI" wait "$id" --out "$TMP/out" --progress none >/dev/null 2>"$TMP/waiting.err" &
waiter=$!
wait_log "$TMP/waiting.err" "job $id waits: no connected worker may take its tasks now"
start_worker "$TMP/worker.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/wcache3"
wait "$waiter" || { cat "$TMP/waiting.err"; fail "gi wait once a worker came"; }
[ "$(grep -c "waits: no connected worker" "$TMP/waiting.err")" = 1 ] ||
    { cat "$TMP/waiting.err"; fail "gi wait did not say once that the job waits for a worker"; }

# Reached with another token: it says which gi-farmd refused it, and what to give.
rc=0
GI_FARM_TOKEN_FILE="$TMP/secret" "$GI" jobs 2>"$TMP/token.err" || rc=$?
[ $rc = 1 ] && grep -q "^gi: /api/v1/jobs: gi-farmd at http://$API (from \$GI_FARM) refused the \
API token: .* (give the token gi-farmd was started with: its --token-file)$" "$TMP/token.err" ||
    { cat "$TMP/token.err"; fail "gi jobs with a wrong token: exit $rc"; }

# A gi-worker pointed at the API port hears nothing: it says what to check.
"$WORKER" --connect "$API" --once --procs 1 --cache "$TMP/wcache2" --name wrongport \
    >"$TMP/wrongport.log" 2>&1 &
wrongport=$!

# A bad --retry is an argument error.
rc=0
"$GI" jobs --retry -1 2>"$TMP/bad.err" || rc=$?
[ $rc = 2 ] && grep -q "\-\-retry must be seconds in \[0, 86400\]" "$TMP/bad.err" ||
    { cat "$TMP/bad.err"; fail "gi jobs --retry -1: exit $rc"; }
# A second gi-farmd on the same API port names the option and the cause.
rc=0
"$FARMD" --state "$TMP/state2" --listen-workers 127.0.0.1:0 --listen-api "$API" 2>"$TMP/second.err" ||
    rc=$?
[ $rc = 1 ] && grep -q "^gi-farmd: --listen-api: cannot listen on $API: Address already in use \
(another program, a gi-farmd perhaps, has that port: give another)$" "$TMP/second.err" ||
    { cat "$TMP/second.err"; fail "a second gi-farmd on the API port (exit $rc)"; }
rc=0
wait "$wrongport" || rc=$?
# (gi-farmd may close the silent connection first: its --api-head-seconds is 10 s too; or
# answer 400 at once when the HELLO's bytes happen to end a malformed request line.)
[ $rc != 0 ] && grep -Eq "(no answer from the coordinator at $API within 10 s|the coordinator at \
$API closed the connection during the handshake without a word|the coordinator at $API \
answered in HTTP): is that" "$TMP/wrongport.log" &&
    grep -qF "is that gi-farmd's worker port (its --listen-workers, 7071 by default), not its \
API port (--listen-api, 7070)?" "$TMP/wrongport.log" || { cat "$TMP/wrongport.log"; fail "gi-worker on the API port (exit $rc)"; }
stop_farmd "$LOG"
echo "ok"
