# A farm whose API connections are all taken (1000 clients at once) turns
# new ones away: `gi` asks again, with a jittered backoff, for up to a
# minute, saying so once, and succeeds once slots free up. GET, HEAD and
# asset PUTs are asked again whatever broke; a submission carries an
# Idempotency-Key, so that one sent again after its answer was lost makes
# no second job (the farm answers it with the first job), also across a
# gi-farmd restart (the key is journaled with its job).
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
LOG="$TMP/farmd.log"
# No minimum rate: the held submissions below, whose bodies never come,
# must keep their slots (farm_api_slow.sh tests the rate).
start_farmd "$TMP/state" "$LOG" -- --api-min-rate 0
start_worker "$TMP/worker.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/cache"
write_job "$TMP/job.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "pt", "seed": 3,
 "image": {"width": 16, "height": 16}, "pt": {"spp": 8, "tile": 16, "pass_spp": 8},
 "outputs": {"exr": "img.exr"}}
JOB
"$GI" submit "$TMP/job.json" --wait --out "$TMP/out1" --progress none >"$TMP/s1.log" 2>&1 ||
    { cat "$TMP/s1.log"; fail "submit"; }

# The API's 64 slots of this address, each held by a submission whose body
# never comes (not idle: no slot is given up for a newcomer), until the
# file $TMP/release appears (the clients below were all turned away), 30 s
# at most.
python3 - "$API" "$(cat "$TMP/token")" "$TMP/release" >"$TMP/hold.out" 2>&1 <<'PY' &
import os, socket, sys, time
host, port = sys.argv[1].rsplit(":", 1)
token = sys.argv[2].encode()
held = []
def hold():
    s = socket.create_connection((host, int(port)))
    s.sendall(b"POST /api/v1/jobs HTTP/1.1\r\nHost: x\r\n"
              b"Authorization: Bearer " + token + b"\r\nContent-Length: 1000\r\n\r\n")
    held.append(s)
def answered():
    s = socket.create_connection((host, int(port)), timeout=10)
    s.sendall(b"GET /api/v1/jobs HTTP/1.1\r\nHost: x\r\nConnection: close\r\n"
              b"Authorization: Bearer " + token + b"\r\n\r\n")
    try:
        return s.recv(64).startswith(b"HTTP/1.1 200")
    except OSError:
        return False
for _ in range(64):
    hold()
# Full once a newcomer is turned away: until gi-farmd has read a held
# request's head, that connection is idle and gives its slot up.
for _ in range(200):
    time.sleep(0.1)
    if not answered():
        break
    hold()
else:
    sys.exit("the slots never filled")
print("holding", flush=True)
for _ in range(300):
    if os.path.exists(sys.argv[3]):
        break
    time.sleep(0.1)
for s in held:
    s.close()
print("released", flush=True)
PY
holder=$!
FARM_PIDS="$FARM_PIDS $holder"
n=0
until grep -q holding "$TMP/hold.out"; do
    n=$((n + 1)); [ $n -lt 200 ] || { cat "$TMP/hold.out"; fail "the holder did not start"; }
    sleep 0.05
done
# Turned away now (the slots are taken, not idle)...
code=$(curl -s -o /dev/null -w '%{http_code}' --max-time 5 \
    -H "Authorization: Bearer $(cat "$TMP/token")" "$GI_FARM/api/v1/jobs/1" || true)
[ "$code" != 200 ] || fail "the slots were not full (HTTP $code)"
# ...yet gi status, gi wait (its outputs too) and gi submit succeed.
"$GI" status 1 >"$TMP/status.out" 2>"$TMP/status.err" &
p1=$!
"$GI" wait 1 --out "$TMP/out2" --progress none >"$TMP/wait.out" 2>"$TMP/wait.err" &
p2=$!
"$GI" submit "$TMP/job.json" >"$TMP/submit.out" 2>"$TMP/submit.err" &
p3=$!
# Each is turned away (it says so) before the slots free up: a fixed hold
# would race their start on a busy machine.
turned_away() {
    for e in status wait submit; do grep -q "asking again" "$TMP/$e.err" 2>/dev/null || return 1; done
}
n=0
until turned_away; do
    n=$((n + 1)); [ $n -lt 400 ] || fail "gi status, wait and submit were not all turned away"
    sleep 0.05
done
: >"$TMP/release"
wait $p1 || { cat "$TMP/status.err"; fail "gi status while the API was full"; }
wait $p2 || { cat "$TMP/wait.err"; fail "gi wait while the API was full"; }
wait $p3 || { cat "$TMP/submit.err"; fail "gi submit while the API was full"; }
wait $holder
grep -q released "$TMP/hold.out" || fail "the holder did not finish"
grep -q "job 1: .* done" "$TMP/status.out" || { cat "$TMP/status.out"; fail "gi status output"; }
cmp "$TMP/out1/img.exr" "$TMP/out2/img.exr" || fail "gi wait's outputs"
for e in status wait submit; do
    [ "$(grep -c "asking again for up to" "$TMP/$e.err")" = 1 ] ||
        { cat "$TMP/$e.err"; fail "gi $e did not say once that it asks again"; }
done
[ "$(cat "$TMP/submit.out")" = 2 ] || { cat "$TMP/submit.out"; fail "not job 2"; }
[ "$("$GI" jobs | awk 'NR > 1' | wc -l)" = 2 ] || { "$GI" jobs; fail "not two jobs"; }

# The key on the API: the same submission again -> the same job (200);
# another submission with that key -> 409; a malformed key -> 400.
h=$(b2sum -l 256 "$SRC/scenes/cornell-box/scene.json" | cut -d' ' -f1)
body='{"job": {"scene": "scene.json", "method": "pt", "image": {"width": 8, "height": 8}},
       "assets": {"scene.json": "'$h'"}}'
key=0123456789abcdef0123456789abcdef
post() { api /api/v1/jobs -o "$TMP/r" -w '%{http_code}' -X POST -H "Idempotency-Key: $1" --data-binary "$2"; }
[ "$(post $key "$body")" = 201 ] || { cat "$TMP/r"; fail "first submission"; }
id=$(grep -o '"id":[0-9]*' "$TMP/r" | cut -d: -f2)
[ "$(post $key "$body")" = 200 ] && grep -q "\"id\":$id," "$TMP/r" || { cat "$TMP/r"; fail "repeated submission"; }
grep -q "job $id: its submission came again with its Idempotency-Key" "$LOG" || fail "not logged"
[ "$(post $key "$(echo "$body" | sed 's/"width": 8/"width": 9/')")" = 409 ] &&
    grep -q "was given to job $id, another submission" "$TMP/r" || { cat "$TMP/r"; fail "key reuse"; }
[ "$(post 'short' "$body")" = 400 ] && grep -q "Idempotency-Key: 16 to 64" "$TMP/r" ||
    { cat "$TMP/r"; fail "a malformed key"; }
[ "$("$GI" jobs | awk 'NR > 1' | wc -l)" = 3 ] || { "$GI" jobs; fail "not three jobs"; }
kill "$WORKER_PID" 2>/dev/null || true

# The key is journaled with its job: a client asking again after gi-farmd
# restarted (it was stopped between the submission and the retry) gets
# the job the first one made, and the key still refuses another
# submission. Twice: the second start reads the journal the first one
# compacted.
for n in 1 2; do
    stop_farmd "$LOG"
    start_farmd "$TMP/state" "$LOG"
    [ "$(post $key "$body")" = 200 ] && grep -q "\"id\":$id," "$TMP/r" ||
        { cat "$TMP/r"; fail "repeated submission after restart $n"; }
    [ "$(post $key "$(echo "$body" | sed 's/"width": 8/"width": 9/')")" = 409 ] &&
        grep -q "was given to job $id, another submission" "$TMP/r" ||
        { cat "$TMP/r"; fail "key reuse after restart $n"; }
    [ "$("$GI" jobs | awk 'NR > 1' | wc -l)" = 3 ] || { "$GI" jobs; fail "not three jobs"; }
done
[ "$(grep -c "job $id: its submission came again with its Idempotency-Key" "$LOG")" = 3 ] ||
    fail "the repeats after the restarts not logged"
# The key lives as long as its job: purged, it is forgotten (restart or not).
api "/api/v1/jobs/$id" -o /dev/null -X DELETE
api "/api/v1/jobs/$id?purge=1" -o "$TMP/r" -X DELETE
grep -q '"purged":true' "$TMP/r" || { cat "$TMP/r"; fail "purge $id"; }
stop_farmd "$LOG"
start_farmd "$TMP/state" "$LOG"
[ "$(post $key "$body")" = 201 ] || { cat "$TMP/r"; fail "the purged job's key is still known"; }
id2=$(grep -o '"id":[0-9]*' "$TMP/r" | cut -d: -f2)
[ "$id2" -gt "$id" ] || fail "job $id2 after $id"
api "/api/v1/jobs/$id2" -o /dev/null -X DELETE
stop_farmd "$LOG"
