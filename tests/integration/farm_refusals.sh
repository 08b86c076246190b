# gi-farmd refuses, each with a logged reason, and keeps serving (and
# refuses to start with one value as API token and farm secret). Every
# refusal is logged in full here (--refusal-log-window 0; farm_refusal_log.sh
# tests the default): a worker with the wrong secret, a worker with no
# protocol version in common, API calls without (or with a wrong) token,
# an oversized frame, a frame with a bad CRC, an unknown message type, frames
# a connection may not carry, an oversized upload, uploads under way past the
# store's limit, jobs that name files
# outside their uploaded assets, and a scene whose parser crashes (in the
# forked checker). Then a job still renders.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
LOG="$TMP/farmd.log"
# The token as the farm secret too: any client could join as a worker.
st=0
GI_FARM_TOKEN_FILE="$TMP/secret" timeout 20 "$FARMD" --state "$TMP/same" --listen-workers 127.0.0.1:0 \
    --listen-api 127.0.0.1:0 >"$TMP/same.log" 2>&1 || st=$?
[ $st -eq 2 ] && grep -q "the API token and the farm secret are the same" "$TMP/same.log" ||
    { cat "$TMP/same.log"; fail "one value as token and secret: exit $st"; }
start_farmd "$TMP/state" "$LOG" -- --heartbeat 0.2 --lease 2 --dead 10 --max-result-bytes 16M \
    --max-asset-bytes 1M --max-store-bytes 2M --api-head-seconds 1 --refusal-log-window 0
logged() { grep -q -- "$1" "$LOG" || { cat "$LOG"; fail "not logged: $1"; }; }

# Wrong farm secret: the worker is refused and says why.
head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \n' >"$TMP/wrong"
chmod 600 "$TMP/wrong"
if "$WORKER" --connect "$WADDR" --procs 1 --cache "$TMP/c0" --secret-file "$TMP/wrong" --once \
    >"$TMP/wrong.log" 2>&1; then fail "a worker with the wrong secret was accepted"; fi
grep -q "authentication failed" "$TMP/wrong.log" || { cat "$TMP/wrong.log"; fail "the worker was not told"; }
logged "refused .*authentication failed: the worker does not know the farm secret"
# A batch directory it cannot write: the worker says so at start (exit 2),
# not at its first task.
: >"$TMP/not-a-dir"
st=0
"$WORKER" --connect "$WADDR" --procs 1 --cache "$TMP/c0" --secret-file "$TMP/secret" --once \
    --batch-dir "$TMP/not-a-dir" >"$TMP/batchdir.log" 2>&1 || st=$?
[ $st -eq 2 ] && grep -q "batch directory: .*not-a-dir: not a directory" "$TMP/batchdir.log" ||
    { cat "$TMP/batchdir.log"; fail "a worker with a file as its batch directory: exit $st"; }

# Malformed frames, before and after authenticating.
peer() {
    out=$(GI_FARM_SECRET_FILE="$TMP/secret" "$RAWPEER" "$WADDR" "$1") || fail "$1: not refused ($out)"
    echo "$out" | grep -q -- "$2" || fail "$1: \"$out\" does not say \"$2\""
    logged "$2"
}
peer oversized "HELLO frame payload of 1073741824 bytes exceeds the limit of 65536 bytes"
peer badcrc "HELLO frame CRC32C mismatch"
peer unknown-type "frame type 99 is unknown"
peer garbage 'bad magic "GET "'
peer version "worker speaks protocol versions 3-4; this coordinator speaks 1-2"
peer result-first "RESULT frames are not accepted on this connection"
peer auth-oversized-result "RESULT frame payload of 67108864 bytes exceeds the limit of 16777216 bytes"
peer auth-badcrc "HELLO frames are not accepted on this connection"
peer auth-unknown-type "frame type 99 is unknown"
peer auth-unexpected "ASSET_PUT frames are not accepted on this connection"

# The API: no token, a wrong token.
code=$(curl -s -o "$TMP/r" -w '%{http_code}' "$GI_FARM/api/v1/jobs")
[ "$code" = 401 ] || fail "no token: HTTP $code"
logged "api: refused GET /api/v1/jobs from 127.0.0.1:[0-9]*: missing bearer token"
code=$(curl -s -o "$TMP/r" -w '%{http_code}' -H "Authorization: Bearer not-the-token" \
    -X POST --data-binary '{}' "$GI_FARM/api/v1/jobs")
[ "$code" = 401 ] || fail "wrong token: HTTP $code"
logged "api: refused POST /api/v1/jobs from .*: wrong bearer token"
! grep -q "$(cat "$TMP/token")" "$LOG" || fail "the token appears in the log"
! grep -q "$(cat "$TMP/secret")" "$LOG" || fail "the secret appears in the log"

# Uploads: over the size limit; bytes that do not match their name.
head -c 2000000 /dev/zero >"$TMP/big"
code=$(api "/api/v1/assets/$(b2sum -l 256 "$TMP/big" | cut -d' ' -f1)" -o "$TMP/r" -w '%{http_code}' \
    -X PUT --data-binary @"$TMP/big")
[ "$code" = 413 ] || fail "oversized upload: HTTP $code"
logged "over the limit of 1048576"
# The same sent chunked (no length to refuse up front): 413 at its end.
code=$(api "/api/v1/assets/$(b2sum -l 256 "$TMP/big" | cut -d' ' -f1)" -o "$TMP/r" -w '%{http_code}' \
    -X PUT -H 'Transfer-Encoding: chunked' --data-binary @"$TMP/big")
[ "$code" = 413 ] || fail "oversized chunked upload: HTTP $code"
# A body where none is taken: 400; a method a path does not take: 405
# with the methods it does.
code=$(api /api/v1/workers -o "$TMP/r" -w '%{http_code}' -X GET --data-binary 'x')
[ "$code" = 400 ] && grep -q "takes no request body" "$TMP/r" || { cat "$TMP/r"; fail "body on GET: HTTP $code"; }
api /api/v1/jobs -X PUT -D "$TMP/h" -o /dev/null
grep -q "^HTTP/1.1 405" "$TMP/h" && grep -qi "^Allow: GET, HEAD, POST" "$TMP/h" || { cat "$TMP/h"; fail "405 without Allow"; }
code=$(api "/api/v1/assets/$(printf 'a%.0s' $(seq 64))" -o "$TMP/r" -w '%{http_code}' -X PUT \
    --data-binary 'not these bytes')
[ "$code" = 400 ] || fail "mismatched upload: HTTP $code"
logged "hash to"
code=$(api "/api/v1/assets/$(printf 'a%.0s' $(seq 300))" -o "$TMP/r" -w '%{http_code}' -X PUT \
    --data-binary 'x')
[ "$code" = 400 ] && ! grep -q "no such endpoint" "$TMP/r" || { cat "$TMP/r"; fail "a 300-character hash: HTTP $code"; }
# Uploads under way count against --max-store-bytes as their bytes arrive:
# three of 900 KiB at once, sent chunked (no length to refuse up front),
# never put more than the store's 2 MiB on disk; the third is refused (507),
# and its bytes no longer count once it is.
st=0
python3 - "$API" "$(cat "$TMP/token")" "$TMP/state/assets/tmp" >"$TMP/uploads.out" 2>&1 \
    <<'PY' || st=$?
import hashlib, os, socket, sys, time
host, port = sys.argv[1].rsplit(":", 1)
conns = []
for k in range(3):
    body = bytes([k]) * (900 << 10)
    name = hashlib.blake2b(body, digest_size=32).hexdigest()
    s = socket.create_connection((host, int(port)))
    s.settimeout(10)
    s.sendall(("PUT /api/v1/assets/%s HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer %s\r\n"
               "Transfer-Encoding: chunked\r\n\r\n" % (name, sys.argv[2])).encode())
    s.sendall(b"%x\r\n%s\r\n" % (len(body), body))
    conns.append(s)
time.sleep(1)
held = sum(os.path.getsize(os.path.join(sys.argv[3], n)) for n in os.listdir(sys.argv[3]))
codes = []
for s in conns:
    s.sendall(b"0\r\n\r\n")
    codes.append(s.recv(64).split(b" ")[1].decode())
    s.close()
print("on disk while under way:", held, "answers:", codes)
sys.exit(0 if held <= 2 << 20 and sorted(codes) == ["201", "201", "507"] else 1)
PY
[ $st -eq 0 ] || { cat "$TMP/uploads.out"; fail "uploads under way past the store's limit"; }
head -c 100000 /dev/urandom >"$TMP/small"
h=$(b2sum -l 256 "$TMP/small" | cut -d' ' -f1)
code=$(api "/api/v1/assets/$h" -o "$TMP/r" -w '%{http_code}' -X PUT --data-binary @"$TMP/small")
[ "$code" = 201 ] || { cat "$TMP/r"; fail "an upload that fits after a refused one: HTTP $code"; }
# Submission bodies held in memory while they arrive: 128 MiB at most for
# all of them. Four of 31 MiB under way; a fifth saying 8 MiB is refused at
# once (503), one sent chunked when its bytes pass the limit; once they are
# in, 8 MiB are read again (400: not a job).
st=0
python3 - "$API" "$(cat "$TMP/token")" >"$TMP/submits.out" 2>&1 <<'PY' || st=$?
import socket, sys, time
host, port = sys.argv[1].rsplit(":", 1)
def post(head):
    s = socket.create_connection((host, int(port)))
    s.settimeout(20)
    s.sendall(("POST /api/v1/jobs HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer %s\r\n%s\r\n"
               % (sys.argv[2], head)).encode())
    return s
def status(s):  # then closed: an idle connection would be cut, and counted
    code = s.recv(64).split(b" ")[1].decode()
    s.close()
    return code
held = []
for _ in range(4):
    held.append(post("Content-Length: %d\r\n" % (32 << 20)))
    held[-1].sendall(b" " * (31 << 20))
time.sleep(1)  # the server has read them
said = status(post("Content-Length: %d\r\n" % (8 << 20)))
chunked = post("Transfer-Encoding: chunked\r\n")
chunked.sendall(b"%x\r\n%s\r\n0\r\n\r\n" % (8 << 20, b" " * (8 << 20)))
print("with 124 MiB under way: 8 MiB said", said, "- 8 MiB chunked", status(chunked))
for s in held:
    s.sendall(b" " * (1 << 20))
    print("one under way, when complete:", status(s))
later = post("Content-Length: %d\r\n" % (8 << 20))
later.sendall(b" " * (8 << 20))
print("8 MiB after them:", status(later))
PY
[ $st -eq 0 ] && grep -q "said 503 - 8 MiB chunked 503" "$TMP/submits.out" &&
    grep -q "after them: 400" "$TMP/submits.out" ||
    { cat "$TMP/submits.out"; fail "submissions under way"; }
logged "submissions under way hold"

# A client trickling its request's head, a line every 0.2 s, is cut off
# after --api-head-seconds; the others are served all the while.
python3 - "${GI_FARM#http://}" >"$TMP/slow.out" 2>&1 <<'PY' &
import socket, sys, time
host, port = sys.argv[1].rsplit(":", 1)
s = socket.create_connection((host, int(port)))
s.sendall(b"GET /api/v1/jobs HTTP/1.1\r\nHost: x\r\n")
t0 = time.time()
try:
    while time.time() - t0 < 8:
        time.sleep(0.2)
        s.sendall(b"X-Slow: 1\r\n")
    print("still open after 8 s")
except OSError:
    print("closed after %.1f s" % (time.time() - t0))
PY
slow=$!
sleep 0.5
code=$(api /api/v1/workers -o /dev/null -w '%{http_code}')
[ "$code" = 200 ] || fail "another client during the slow one: HTTP $code"
wait $slow
grep -q "^closed after [1-3]\." "$TMP/slow.out" || { cat "$TMP/slow.out"; fail "the slow client was not cut off"; }
api /metrics | grep -q "^gi_farm_api_slow_closed_total 1" || fail "the cut is not counted"

# Jobs naming files outside their assets.
job_body() { # SCENE ASSETS-JSON
    printf '{"job": {"scene": "%s", "method": "pt", "image": {"width": 8, "height": 8}}, "assets": %s}' "$1" "$2"
}
code=$(api /api/v1/jobs -o "$TMP/r" -w '%{http_code}' -X POST --data-binary "$(job_body ../../../etc/passwd '{}')")
[ "$code" = 400 ] || fail "scene outside the assets: HTTP $code"
grep -q "not among the job's assets" "$TMP/r" || { cat "$TMP/r"; fail "no reason given"; }
logged 'scene: "../../../etc/passwd" is not among the job'"'"'s assets'
code=$(api /api/v1/jobs -o "$TMP/r" -w '%{http_code}' -X POST \
    --data-binary "$(job_body s.json '{"s.json": "'"$(printf 'b%.0s' $(seq 64))"'"}')")
[ "$code" = 400 ] && grep -q "was never uploaded" "$TMP/r" || { cat "$TMP/r"; fail "asset never uploaded"; }
# A scene that reaches for a file it did not upload: accepted, then failed by the checker.
cat >"$TMP/escape.json" <<SCENE
{"materials": {"l": {"emission": [1, 1, 1]}},
 "objects": [{"name": "lamp", "material": "l", "quad": {"size": [1, 1]}},
             {"name": "loot", "mesh": "../../../../../../etc/hostname"}]}
SCENE
h=$(b2sum -l 256 "$TMP/escape.json" | cut -d' ' -f1)
api "/api/v1/assets/$h" -o /dev/null -X PUT --data-binary @"$TMP/escape.json"
api /api/v1/jobs -o "$TMP/r" -X POST --data-binary "$(job_body escape.json '{"escape.json": "'"$h"'"}')"
id=$(grep -o '"id":[0-9]*' "$TMP/r" | cut -d: -f2)
wait_state "$id" failed 30
api "/api/v1/jobs/$id" | grep -q "etc/hostname: not among the job's assets" || fail "no reason for the escape"
logged "job $id: failed: .*etc/hostname: not among the job's assets"

# A scene checker that crashes (as on a hostile mesh) fails that job only.
stop_farmd "$LOG"
start_farmd "$TMP/state" "$LOG" env GI_FAULT_CHECK_CRASH=1 -- --heartbeat 0.2 --lease 2 --dead 10
api /api/v1/jobs -o "$TMP/r" -X POST --data-binary "$(job_body escape.json '{"escape.json": "'"$h"'"}')"
id=$(grep -o '"id":[0-9]*' "$TMP/r" | cut -d: -f2)
wait_state "$id" failed 30
logged "job $id: failed: .*loading the scene crashed (signal 11)"
stop_farmd "$LOG"

# Still serving: a job renders (ASan worker, so its children are checked too).
start_farmd "$TMP/state" "$LOG" -- --heartbeat 0.2 --lease 2 --dead 10
WORKER=$WORKER_ASAN start_worker "$TMP/worker.log" -- --connect "$WADDR" --procs 2 --cache "$TMP/cache"
write_job "$TMP/job.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "pt", "image": {"width": 32, "height": 32},
 "pt": {"spp": 4, "tile": 16}, "outputs": {"exr": "img.exr"}}
JOB
"$GI" submit "$TMP/job.json" --wait --out "$TMP/out" --progress none >"$TMP/submit.log" 2>&1 ||
    { cat "$TMP/submit.log"; fail "a job after the refusals"; }
"$GI_RELEASE" render "$TMP/job.json" --workers 1 --out "$TMP/ref" --progress none >/dev/null 2>&1
cmp "$TMP/ref/img.exr" "$TMP/out/img.exr" || fail "image differs"
kill -TERM "$WORKER_PID"
wait "$WORKER_PID" || fail "the worker did not drain cleanly"
! grep -q "LeakSanitizer\|AddressSanitizer\|runtime error" "$TMP/worker.log" || { cat "$TMP/worker.log"; fail "sanitizer"; }
stop_farmd "$LOG"
echo "every refusal logged; the farm still renders"
