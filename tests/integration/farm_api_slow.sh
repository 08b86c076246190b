# Slow clients cannot hold the API's slots (a slowloris). With no one
# waiting for a slot, trickled submission bodies are closed after
# --api-request-seconds, while a body sent at twice --api-min-rate (longer
# than --api-request-seconds) gets its answer. A client holding every slot
# of its address (64) with token-bearing submissions whose bodies come a
# byte at a time, and header lines trickled without a token, each reopened
# as soon as it is closed: a normal client from that address still submits,
# waits and fetches its outputs meanwhile, never turned away, and the first
# 64 are all closed within a few seconds. An upload and a download at a
# slow but sufficient rate get through. The log says why connections were
# closed, a line per window, not one per connection (nor one per connection
# from libmicrohttpd). Last, with a deadline longer than the test, 64
# trickled submissions give their slots up to a normal client once they
# are behind the rate.
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
    FARM_PIDS="$FARM_PIDS $holder"
    n=0
    until grep -q holding "$TMP/hold.out" 2>/dev/null; do
        n=$((n + 1)); [ $n -lt 200 ] || { cat "$TMP/hold.out"; fail "the holder did not start"; }
        sleep 0.05
    done
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

# An upload and a download at 8 KiB/s (2.5 s each, past --api-request-seconds).
head -c 20000 /dev/urandom >"$TMP/asset"
h=$(b2sum -l 256 "$TMP/asset" | cut -d' ' -f1)
code=$(api "/api/v1/assets/$h" -o "$TMP/r" -w '%{http_code}' -X PUT --limit-rate 8K \
    --data-binary @"$TMP/asset")
[ "$code" = 201 ] || { cat "$TMP/r"; fail "a slow but sufficient upload: HTTP $code"; }
api /api/v1/jobs/1/outputs/img.exr -o "$TMP/slow.exr" --limit-rate 8K ||
    fail "a slow but sufficient download"
cmp "$TMP/out/img.exr" "$TMP/slow.exr" || fail "the slow download differs"

# Why, once per window (3 s here): of 100 and more connections closed, a
# line per window and its count at its end. The first, with the deadline's
# reason, came from the requests above; the holder's were counted.
grep -q "closed the connection of 127.0.0.1:[0-9]*: its request (POST /api/v1/jobs) moved [0-9]* bytes in [0-9.]* s, short of --api-request-seconds (1 s) and --api-min-rate (1024 bytes/s)" "$LOG" ||
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
start_farmd "$TMP/state" "$LOG2" -- --api-request-seconds 60 --api-min-rate 1K
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
stop_farmd "$LOG2"
