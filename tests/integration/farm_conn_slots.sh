# Clients that open connections and send nothing cannot keep others out.
# The API: 64 idle connections from one address (MHD's limit per address),
# then 64 from each of four more (its limit in all): a client still gets its
# answer, because the longest idle connection gives its slot up. The worker
# port: a peer without the secret holding 100 connections, opening a new one
# as each closes, does not keep a worker from joining, and its refusals do
# not write a log line each.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
LOG="$TMP/farmd.log"
# A head deadline longer than the test: no slot frees itself meanwhile.
start_farmd "$TMP/state" "$LOG" -- --max-workers 2 --api-head-seconds 60

st=0
python3 - "$API" "$(cat "$TMP/token")" >"$TMP/api.out" 2>&1 <<'PY' || st=$?
import socket, sys
host, port = sys.argv[1].rsplit(":", 1)
token = sys.argv[2]
held = []
def hold(src, n):
    for _ in range(n):
        s = socket.socket()
        s.bind((src, 0))
        s.connect((host, int(port)))
        held.append(s)
def ask(src):
    s = socket.socket()
    s.settimeout(10)
    s.bind((src, 0))
    s.connect((host, int(port)))
    s.sendall(("GET /api/v1/workers HTTP/1.1\r\nHost: x\r\nConnection: close\r\n"
               "Authorization: Bearer %s\r\n\r\n" % token).encode())
    try:
        return s.recv(64).split(b"\r\n")[0].decode()
    except OSError as e:
        return repr(e)
hold("127.0.0.1", 64)
got = ask("127.0.0.1")
print("64 idle from this address:", got)
if "200" not in got:
    sys.exit(1)
for k in range(2, 6):
    hold("127.0.0.%d" % k, 64)
got = ask("127.0.0.1")
print("idle connections from five addresses:", got)
if "200" not in got:
    sys.exit(1)
PY
[ $st -eq 0 ] || { cat "$TMP/api.out"; fail "a client was kept out by idle connections"; }
[ "$(metric gi_farm_api_conns_shed_total)" -ge 2 ] || fail "the evictions are not counted"

python3 - "$WADDR" >"$TMP/flood.out" 2>&1 <<'PY' &
import selectors, socket, sys, time
host, port = sys.argv[1].rsplit(":", 1)
sel = selectors.DefaultSelector()
def connect():
    s = socket.create_connection((host, int(port)))
    s.setblocking(False)
    sel.register(s, selectors.EVENT_READ)
for _ in range(100):
    connect()
print("holding", flush=True)
t0, again = time.time(), 0
while time.time() - t0 < 8:
    for key, _ in sel.select(0.1):
        try:
            data = key.fileobj.recv(4096)
        except OSError:
            data = b""
        if not data:
            sel.unregister(key.fileobj)
            key.fileobj.close()
            connect()
            again += 1
print("reconnected", again)
PY
flood=$!
FARM_PIDS="$FARM_PIDS $flood"
n=0
until grep -q holding "$TMP/flood.out"; do
    n=$((n + 1)); [ $n -lt 100 ] || fail "the flood did not start"; sleep 0.05
done
start_worker "$TMP/worker.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/cache"
# Before the flood's first connections time out (10 s): no slot frees by itself.
n=0
until grep -q "connected to" "$TMP/worker.log"; do
    n=$((n + 1))
    [ $n -lt 50 ] || { cat "$TMP/worker.log"; fail "the worker did not join during the flood"; }
    sleep 0.1
done
wait $flood
[ "$(metric gi_farm_worker_handshakes_displaced_total)" -ge 1 ] || fail "not counted"
lines=$(grep -c "a newer connection needed its place" "$LOG")
[ "$lines" -ge 1 ] && [ "$lines" -le 3 ] || fail "$lines log lines for the displaced handshakes"
kill "$WORKER_PID" 2>/dev/null || true
stop_farmd "$LOG"
