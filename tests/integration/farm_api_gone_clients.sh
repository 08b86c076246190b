# Clients that leave mid-request free their API slots at once. A request
# head whose client closed the connection right after sending it (killed,
# or a script that writes and closes) reaches gi-farmd with its FIN, which
# libmicrohttpd, reading edge-triggered, never read: such connections sat
# in close-wait holding their slots until their request's deadline (60 s
# here). Now they are closed within a second, submissions and uploads
# whose bodies never come, and a head cut short. A client that shuts its
# sending side after a whole request still gets its whole answer: a small
# one, and an output read slowly (for a few of gi-farmd's looks).
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
LOG="$TMP/farmd.log"
start_farmd "$TMP/state" "$LOG" -- --api-request-seconds 60 --api-min-rate 1K \
    --api-head-seconds 60
start_worker "$TMP/worker.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/cache"
cornell_job "$TMP/job.json" 3 64 64 4 4
"$GI" submit "$TMP/job.json" --wait --out "$TMP/out" --progress none >"$TMP/submit.log" 2>&1 ||
    { cat "$TMP/submit.log"; fail "gi submit --wait"; }
wait_api_conns 0

python3 - "$API" "$(cat "$TMP/token")" >"$TMP/gone.out" 2>&1 <<'PY' || { cat "$TMP/gone.out"; fail "the clients"; }
import socket, sys
host, port = sys.argv[1].rsplit(":", 1)
auth = b"Authorization: Bearer " + sys.argv[2].encode() + b"\r\n"
heads = [b"POST /api/v1/jobs HTTP/1.1\r\nHost: x\r\n" + auth + b"Content-Length: 100000\r\n\r\n",
         b"PUT /api/v1/assets/" + b"c" * 64 + b" HTTP/1.1\r\nHost: x\r\n" + auth +
         b"Content-Length: 100000\r\n\r\n{",
         b"GET /api/v1/jobs HTTP/1.1\r\nHost: x\r\n" + auth]
for k in range(30):
    s = socket.create_connection((host, int(port)))
    s.sendall(heads[k % 3])
    s.close()
print("30 clients gone")
PY
wait_api_conns 0

# Half-closed after a whole request: the answer comes whole.
python3 - "$API" "$(cat "$TMP/token")" "$TMP/out/img.exr" >"$TMP/half.out" 2>&1 <<'PY' ||
import socket, sys, time
host, port = sys.argv[1].rsplit(":", 1)
auth = b"Authorization: Bearer " + sys.argv[2].encode() + b"\r\n"
ref = open(sys.argv[3], "rb").read()
def ask(path, pace):
    s = socket.socket()
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    s.connect((host, int(port)))
    s.settimeout(30)
    s.sendall(b"GET " + path + b" HTTP/1.1\r\nHost: x\r\nConnection: close\r\n" + auth + b"\r\n")
    s.shutdown(socket.SHUT_WR)
    buf = b""
    while True:
        time.sleep(pace)
        piece = s.recv(4096)
        if not piece:
            return buf
        buf += piece
small = ask(b"/api/v1/workers", 0)
print("workers:", small.split(b"\r\n")[0].decode())
t = time.time()
out = ask(b"/api/v1/jobs/1/outputs/img.exr", 0.15)
body = out[out.find(b"\r\n\r\n") + 4:]
print("output:", out.split(b"\r\n")[0].decode(), "in %.1f s," % (time.time() - t),
      "whole" if body == ref else "%d bytes of %d" % (len(body), len(ref)))
PY
    { cat "$TMP/half.out"; fail "half-closed clients"; }
grep -q "workers: HTTP/1.1 200 OK" "$TMP/half.out" || fail "a half-closed client's small answer"
grep -q "output: HTTP/1.1 200 OK in [1-9][0-9]*\.[0-9] s, whole" "$TMP/half.out" || fail "a half-closed client's output"
kill "$WORKER_PID" 2>/dev/null || true
stop_farmd "$LOG"
