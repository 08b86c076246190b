# Slow clients cannot hold the API's slots (a slowloris). With no one
# waiting for a slot, trickled submission bodies are closed after
# --api-request-seconds, while a body sent at twice --api-min-rate (longer
# than --api-request-seconds) gets its answer. A client holding every slot
# of its address (64) with token-bearing submissions whose bodies come a
# byte at a time, and header lines trickled without a token, each reopened
# as soon as it is closed: a normal client from that address still submits,
# waits and fetches its outputs meanwhile, never turned away, and the first
# 64 are all closed within a few seconds. A download at a slow but
# sufficient rate gets through. The log says why connections were closed,
# a line per window, not one per connection (nor one per connection from
# libmicrohttpd). Then, with more time in hand than the test takes, 64
# trickled submissions give their slots up to a normal client once they
# are behind the rate, and so do 64 uploads that sent fast and stopped.
# Last, a download read fast and then not at all and an upload sent fast
# and then stopped are closed --api-request-seconds after they stopped,
# while others are answered, and steady ones at a few times the rate,
# uploads and downloads, are not closed.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
LOG="$TMP/farmd.log"
start_farmd "$TMP/state" "$LOG" -- --api-request-seconds 1 --api-min-rate 1K \
    --api-head-seconds 1 --refusal-log-window 3
t_start=$(date +%s)
start_worker "$TMP/worker.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/cache"
cornell_job "$TMP/job.json" 3 16 16 4 4

# No one waits for a slot: only the deadline closes. Three trickled
# bodies are closed after 1 s (and before 4 s); one sent at 2 KiB/s (3 s,
# twice the minimum rate) gets its answer (400: not a job).
st=0
python3 - "$API" "$(cat "$TMP/token")" >"$TMP/pace.out" 2>&1 <<'PY' || st=$?
import socket, sys, time
host, port = sys.argv[1].rsplit(":", 1)
token = sys.argv[2].encode()
def post(n):
    s = socket.create_connection((host, int(port)))
    s.settimeout(10)
    s.sendall(b"POST /api/v1/jobs HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer " + token +
              b"\r\nContent-Length: %d\r\n\r\n" % n)
    return s
slow = [post(100000) for _ in range(3)]
paced = post(205 * 30)
t0 = time.time()
ends, sent = {}, 0
while len(ends) < 3 and time.time() - t0 < 10:
    time.sleep(0.1)
    if sent < 30:
        paced.sendall(b" " * 205)
        sent += 1
    for i, s in enumerate(slow):
        if i in ends:
            continue
        try:
            s.sendall(b" ")
        except OSError:
            ends[i] = time.time() - t0
while sent < 30:
    time.sleep(0.1)
    paced.sendall(b" " * 205)
    sent += 1
print("trickled closed after", sorted("%.1f" % e for e in ends.values()))
print("paced:", paced.recv(64).split(b"\r\n")[0].decode())
sys.exit(0 if len(ends) == 3 and all(1 <= e < 4 for e in ends.values()) else 1)
PY
[ $st -eq 0 ] && grep -q "paced: HTTP/1.1 400" "$TMP/pace.out" ||
    { cat "$TMP/pace.out"; fail "the deadline of a request"; }
# started PID OUT WORD: the client PID (killed at the end if still there)
# has written WORD to OUT, within 60 s (10 s was too short under the full
# suite's load for the 64 uploads of 100 KB; a client that is quicker
# returns at once).
started() {
    FARM_PIDS="$FARM_PIDS $1"
    n=0
    until grep -q "$3" "$2" 2>/dev/null; do
        n=$((n + 1)); [ $n -lt 1200 ] || { cat "$2"; fail "$2: no \"$3\" from the client"; }
        sleep 0.05
    done
}

# hold HEADS: all of 127.0.0.1's 64 slots, 64 - HEADS trickled submissions
# and HEADS trickled heads, a byte or a line every 0.2 s, each reopened when
# it is closed, until $TMP/release appears and, with HEADS > 0, the first
# 64 were all closed (60 s at most). It says how long the first 64 lived and
# how many were closed, in $TMP/hold.out. Sets holder (its pid).
hold() {
    rm -f "$TMP/release" "$TMP/hold.out"
    python3 - "$API" "$(cat "$TMP/token")" "$TMP/release" "$1" >"$TMP/hold.out" 2>&1 <<'PY' &
import os, select, socket, sys, time
host, port = sys.argv[1].rsplit(":", 1)
token = sys.argv[2].encode()
def body():
    s = socket.create_connection((host, int(port)))
    s.sendall(b"POST /api/v1/jobs HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer " + token +
              b"\r\nContent-Length: 100000\r\n\r\n")
    return s
def head():
    s = socket.create_connection((host, int(port)))
    s.sendall(b"GET /api/v1/jobs HTTP/1.1\r\nHost: x\r\n")
    return s
def gone(s):  # closed by the server: readable (EOF or a reset), or a send fails
    try:
        s.sendall(b" " if s in bodies else b"X-Slow: 1\r\n")
        return bool(select.select([s], [], [], 0)[0]) and not s.recv(4096)
    except OSError:
        return True
heads = int(sys.argv[4])
conns = [[body() if k >= heads else head(), time.time(), k >= heads, True]
         for k in range(64)]
bodies = {c[0] for c in conns if c[2]}
print("holding", flush=True)
lived, closed = [], 0
t0 = time.time()
while (not os.path.exists(sys.argv[3]) or (heads and len(lived) < 64)) and \
        time.time() - t0 < 60:
    time.sleep(0.2)
    for c in conns:
        if not gone(c[0]):
            continue
        c[0].close()
        closed += 1
        if c[3]:
            lived.append(time.time() - c[1])
        c[:] = [body() if c[2] else head(), time.time(), c[2], False]
        if c[2]:
            bodies.add(c[0])
print("first 64 closed: %d, longest lived %.1f s; closed in all: %d"
      % (len(lived), max(lived, default=0), closed), flush=True)
PY
    holder=$!
    started $holder "$TMP/hold.out" holding
}

# 48 trickled submissions and 16 trickled heads.
hold 16
"$GI" submit "$TMP/job.json" --wait --out "$TMP/out" --progress none >"$TMP/submit.log" 2>&1 ||
    { cat "$TMP/submit.log"; fail "gi submit --wait while slow clients held the slots"; }
! grep -q "asking again" "$TMP/submit.log" || { cat "$TMP/submit.log"; fail "gi was turned away"; }
[ -s "$TMP/out/img.exr" ] || fail "no output fetched"
"$GI" fetch 1 --out "$TMP/out2" >"$TMP/fetch.log" 2>&1 || { cat "$TMP/fetch.log"; fail "gi fetch"; }
cmp "$TMP/out/img.exr" "$TMP/out2/img.exr" || fail "the outputs differ"
cmp "$TMP/out/img.exr" "$TMP/job.json.ref/img.exr" || fail "not the output of gi render"
: >"$TMP/release"
wait $holder || { cat "$TMP/hold.out"; fail "the holder"; }
grep -q "first 64 closed: 64, longest lived [0-4]\." "$TMP/hold.out" ||
    { cat "$TMP/hold.out"; fail "the slow connections were not all closed in time"; }

# A download at 8 KiB/s (an upload: below, curl's pace has 1 s pauses).
api /api/v1/jobs/1/outputs/img.exr -o "$TMP/slow.exr" --limit-rate 8K ||
    fail "a slow but sufficient download"
cmp "$TMP/out/img.exr" "$TMP/slow.exr" || fail "the slow download differs"

# Why, once per window (3 s here): of 100 and more connections closed, a
# line per window and its count at its end. The first, with the deadline's
# reason, came from the requests above; the holder's were counted.
grep -q "closed the connection of 127.0.0.1:[0-9]*: its request (POST /api/v1/jobs) fell --api-request-seconds (1 s) behind --api-min-rate (1024 bytes/s)" "$LOG" ||
    fail "a request's closing not logged with its reason"
wait_log "$LOG" "more refusals from 127.0.0.1 in the last"
# gi's connections took slots the holder's slow ones gave up.
[ "$(metric gi_farm_api_conns_shed_total)" -ge 1 ] || fail "no slot was freed for gi"
windows=$(( ($(date +%s) - t_start) / 3 + 2 ))
lines=$(grep -c "closed the connection of\|more refusals from 127.0.0.1" "$LOG" || true)
mhd=$(grep -c "info: api: " "$LOG" || true)
[ "$lines" -ge 2 ] && [ "$lines" -le $((2 * windows)) ] && [ "$mhd" -le $((2 * windows)) ] ||
    fail "$lines lines for the closed connections, $mhd from libmicrohttpd ($windows windows)"
kill "$WORKER_PID" 2>/dev/null || true
stop_farmd "$LOG"

# Slots go to requests that keep the pace. With a deadline longer than the
# test, 64 trickled submissions hold every slot of 127.0.0.1; once they are
# a second under way, and so behind --api-min-rate, each new connection
# makes the one furthest behind give its slot up: gi submits and fetches,
# never turned away, and no request reaches its deadline.
LOG2="$TMP/farmd2.log"
start_farmd "$TMP/state" "$LOG2" -- --api-request-seconds 60 --api-min-rate 1K \
    --refusal-log-window 0
hold 0
# Until a client was let in for one of them (before, one whose head was not
# read yet, idle, may give its slot up; or the client is turned away).
n=0
until grep -q "is behind --api-min-rate" "$LOG2"; do
    api /api/v1/workers -o /dev/null 2>/dev/null || true
    n=$((n + 1)); [ $n -lt 100 ] || fail "no slot was given up by the trickled submissions"
    sleep 0.05
done
"$GI" submit "$TMP/job.json" >"$TMP/submit2.log" 2>&1 || { cat "$TMP/submit2.log"; fail "gi submit"; }
"$GI" fetch 1 --out "$TMP/out3" >"$TMP/fetch3.log" 2>&1 || { cat "$TMP/fetch3.log"; fail "gi fetch"; }
! grep -q "asking again" "$TMP/submit2.log" "$TMP/fetch3.log" || fail "gi was turned away"
cmp "$TMP/out/img.exr" "$TMP/out3/img.exr" || fail "the outputs differ"
: >"$TMP/release"
wait $holder || { cat "$TMP/hold.out"; fail "the holder"; }
grep -q "closed the connection of 127.0.0.1:[0-9]*: its request (POST /api/v1/jobs) is behind --api-min-rate (1024 bytes/s) and its slot was needed" "$LOG2" ||
    fail "a slot given up not logged with its reason"
[ "$(metric gi_farm_api_conns_shed_total)" -ge 3 ] && [ "$(metric gi_farm_api_slow_requests_closed_total)" = 0 ] ||
    { api /metrics | grep api_; fail "slots given up: not counted, or deadlines reached"; }

# Uploads that sent 100 KB (at 1 KiB/s, 100 s of credit if averaged since
# the head) and then stopped hold every slot of 127.0.0.1: a second after
# they stopped they are behind, and a new client is let in for one.
# The holder's connections all closed first: a slot still held by one would
# take the place of an upload below (which one is shed is then up to timing).
wait_api_conns 0
shed=$(metric gi_farm_api_conns_shed_total)
rm -f "$TMP/release"
python3 - "$API" "$(cat "$TMP/token")" "$TMP/release" >"$TMP/uploads.out" 2>&1 <<'PY' &
import os, select, socket, sys, time
host, port = sys.argv[1].rsplit(":", 1)
# A connect or send that gi-farmd never takes raises (its traceback in
# uploads.out says which), rather than hanging the client unexplained.
socket.setdefaulttimeout(30)
def upload():
    s = socket.create_connection((host, int(port)))
    s.sendall(b"PUT /api/v1/assets/%s HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer %s\r\n"
              b"Content-Length: 1000000\r\n\r\n" % (b"b" * 64, sys.argv[2].encode()))
    return s
def stall(conns):
    # Their heads read (2 s, for a loaded machine: a head still unread is an
    # idle connection, which a newcomer may shed): the bytes below count as
    # moved by the requests.
    time.sleep(2)
    for s in conns:
        s.sendall(b"x" * 100000)
# A 64th coming while the others' heads are not read yet (they are idle)
# would shed one of them: it comes once they are under way, not behind.
conns = [upload() for _ in range(63)]
print("63 heads sent", flush=True)
stall(conns)
print("63 bodies sent", flush=True)
conns.append(upload())
stall(conns[-1:])
if select.select(conns, [], [], 0)[0]:
    sys.exit("closed before they all stopped")
print("stopped", flush=True)
t0 = time.time()
while not os.path.exists(sys.argv[3]) and time.time() - t0 < 60:
    time.sleep(0.1)
print("closed by gi-farmd: %d" % len(select.select(conns, [], [], 0)[0]))
PY
uploader=$!
started $uploader "$TMP/uploads.out" '^stopped$'
sleep 2
api /api/v1/workers -o /dev/null || fail "a client turned away by uploads that stopped"
: >"$TMP/release"
wait $uploader || { cat "$TMP/uploads.out"; fail "the uploads"; }
grep -q "closed by gi-farmd: [1-9]" "$TMP/uploads.out" || { cat "$TMP/uploads.out"; fail "uploads"; }
grep -q "closed the connection of 127.0.0.1:[0-9]*: its request (PUT /api/v1/assets/b*) is behind --api-min-rate (1024 bytes/s) and its slot was needed" "$LOG2" ||
    fail "an upload's slot given up not logged with its reason"
[ "$(metric gi_farm_api_conns_shed_total)" -gt "$shed" ] &&
    [ "$(metric gi_farm_api_slow_requests_closed_total)" = 0 ] ||
    { api /metrics | grep api_; fail "the uploads' slots: not counted, or deadlines reached"; }
stop_farmd "$LOG2"

# A request's credit holds --api-request-seconds at most, however many
# bytes it moved: a download read fast (200 KB, at 4 KiB/s 50 s of credit
# if averaged since the head) and then not at all, and an upload sent fast
# and then stopped, are each closed about 3 s after they stopped (the test
# allows 2 to 15 s; before, only libmicrohttpd's 60 s without a byte
# closed them), while another client is answered every half second. An
# upload and a download at 16 KiB/s (4 x --api-min-rate, 10 s and 12 s:
# past their 3 s many times over) are not cut: the download then reads its
# rest at full speed and has every byte of the output.
LOG3="$TMP/farmd3.log"
start_farmd "$TMP/state3" "$LOG3" -- --api-request-seconds 3 --api-min-rate 4K \
    --refusal-log-window 0
start_worker "$TMP/worker3.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/cache3"
write_job "$TMP/big.json" <<JOB
{
  "scene": "$SRC/scenes/cornell-box/scene.json",
  "method": "pt",
  "seed": 1,
  "image": {"width": 1024, "height": 1024},
  "pt": {"spp": 1, "tile": 64, "pass_spp": 1},
  "outputs": {"exr": "img.exr"}
}
JOB
"$GI" submit "$TMP/big.json" --wait --out "$TMP/big" --progress none >"$TMP/big.log" 2>&1 ||
    { cat "$TMP/big.log"; fail "gi submit --wait of the large job"; }
# Larger than the kernel's largest send buffer (net.ipv4.tcp_wmem, 4 MiB by
# default), so that the answer is still under way (not all handed to the
# kernel) when its reader stops.
[ "$(wc -c <"$TMP/big/img.exr")" -gt 8000000 ] || fail "the large job's output is too small"
st=0
tok=$(cat "$TMP/token")
python3 - "$API" "$tok" "$LOG3" "$TMP/big/img.exr" >"$TMP/stall.out" 2>&1 <<'PY' || st=$?
import hashlib, os, select, socket, sys, threading, time
host, port = sys.argv[1].rsplit(":", 1)
token, log, ref = sys.argv[2].encode(), sys.argv[3], open(sys.argv[4], "rb").read()
out = {}
def conn(rcvbuf=0):  # a small receive buffer: the kernel acknowledges what is read, and
    s = socket.socket()  # little more
    if rcvbuf:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
    s.connect((host, int(port)))
    s.settimeout(60)
    return s
def head(s, method, path, length=None):
    cl = b"Content-Length: %d\r\n" % length if length is not None else b""
    s.sendall(b"%s %s HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer %s\r\n%s\r\n" % (
        method, path, token, cl))
def closed_line(s):  # gi-farmd's line for this connection closed, if any yet
    mark = "closed the connection of 127.0.0.1:%d:" % s.getsockname()[1]
    return next((l.strip() for l in open(log, errors="replace") if mark in l), None)
def stalled_download():
    s = conn(16384)
    head(s, b"GET", b"/api/v1/jobs/1/outputs/img.exr")
    got = 0
    while got < 200000:
        got += len(s.recv(65536))
    stop = time.time()
    while not closed_line(s) and time.time() - stop < 40:
        time.sleep(0.1)
    out["download stalled"] = (time.time() - stop, closed_line(s))
def stalled_upload():
    s = conn()
    head(s, b"PUT", b"/api/v1/assets/" + b"a" * 64, 1000000)
    time.sleep(0.5)  # the head read first: the body counts as moved by the request
    s.sendall(b"x" * 200000)
    stop = time.time()
    try:  # closed by gi-farmd: readable, at its end or reset
        select.select([s], [], [], 40)
        s.recv(4096)
    except OSError:
        pass
    out["upload stalled"] = (time.time() - stop, closed_line(s))
def steady_upload():
    data = os.urandom(160 << 10)
    s = conn()
    name = hashlib.blake2b(data, digest_size=32).hexdigest().encode()
    head(s, b"PUT", b"/api/v1/assets/" + name, len(data))
    t0 = time.time()
    for k in range(0, len(data), 4096):  # 4 KiB every 0.25 s, late pieces caught up
        time.sleep(max(0, t0 + k / 16384 - time.time()))
        s.sendall(data[k:k + 4096])
    out["upload steady"] = (s.recv(64).split(b"\r\n")[0].decode(), closed_line(s))
def steady_download():
    s = conn(16384)
    head(s, b"GET", b"/api/v1/jobs/1/outputs/img.exr")
    t0, buf, piece = time.time(), b"", b" "
    while piece and time.time() - t0 < 12:  # 16 KiB/s for 12 s, then the rest at once
        time.sleep(0.05)
        while piece and len(buf) < (time.time() - t0) * 16384:
            piece = s.recv(4096)
            buf += piece
    while piece and len(buf) < buf.find(b"\r\n\r\n") + 4 + len(ref):
        piece = s.recv(65536)
        buf += piece
    body = buf[buf.find(b"\r\n\r\n") + 4:]
    out["download steady"] = (buf.split(b"\r\n")[0].decode(), body == ref, closed_line(s))
workers = [threading.Thread(target=f) for f in
           (stalled_download, stalled_upload, steady_upload, steady_download)]
for w in workers:
    w.start()
served = []  # another client meanwhile: a request every half second
while any(w.is_alive() for w in workers):
    t = time.time()
    try:
        s = conn()
        head(s, b"GET", b"/api/v1/workers")
        served.append((s.recv(64).split(b"\r\n")[0].decode(), time.time() - t))
        s.close()
    except OSError as e:
        served.append((str(e), time.time() - t))
    time.sleep(0.5)
for w in workers:
    w.join()
for k in sorted(out):
    print(k, out[k])
print("served: %d requests, %d answered 200, the slowest in %.1f s" % (
    len(served), sum(r[0] == "HTTP/1.1 200 OK" for r in served), max(r[1] for r in served)))
ok = all(2 <= out[k][0] <= 15 and out[k][1] for k in ("download stalled",
                                                      "upload stalled"))
ok &= out["upload steady"] == ("HTTP/1.1 201 Created", None)
ok &= out["download steady"] == ("HTTP/1.1 200 OK", True, None)
ok &= len(served) >= 10 and all(r[0] == "HTTP/1.1 200 OK" and r[1] < 5 for r in served)
sys.exit(0 if ok else 1)
PY
[ $st -eq 0 ] || { cat "$TMP/stall.out"; fail "requests that stopped, and steady ones"; }
cat "$TMP/stall.out"
grep -q "closed the connection of 127.0.0.1:[0-9]*: its request (GET /api/v1/jobs/1/outputs/img.exr) fell --api-request-seconds (3 s) behind --api-min-rate (4096 bytes/s): [0-9]* bytes moved in the last [0-9.]* s, [0-9]* in [0-9.]* s in all" "$LOG3" ||
    fail "a stalled download's closing not logged with its reason"
# curl's --limit-rate sends a second's worth at once, then waits for the
# next second: at 16 KiB/s, 64 KiB in 4 s, 2 s of the 3 in hand to spare.
head -c 65536 /dev/urandom >"$TMP/asset"
h=$(b2sum -l 256 "$TMP/asset" | cut -d' ' -f1)
code=$(api "/api/v1/assets/$h" -o "$TMP/r" -w '%{http_code}' -X PUT --limit-rate 16K \
    --data-binary @"$TMP/asset")
[ "$code" = 201 ] || { cat "$TMP/r"; fail "a slow but sufficient upload: HTTP $code"; }
[ "$(metric gi_farm_api_slow_requests_closed_total)" = 2 ] ||
    { api /metrics | grep api_; fail "not two requests closed for their pace"; }
kill "$WORKER_PID" 2>/dev/null || true
stop_farmd "$LOG3"
