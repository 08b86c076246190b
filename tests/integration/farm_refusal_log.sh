# Refusals of peers that have not authenticated do not fill gi-farmd's
# log: per peer address, the first is logged in full (the peer and the
# reason), the others in the window after it as one line with their count
# (a window of 1 s here; 10 s by default). 300 API calls with a wrong
# token and 50 worker connections sending garbage write a handful of lines;
# /metrics counts every one.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
LOG="$TMP/farmd.log"
start_farmd "$TMP/state" "$LOG" -- --refusal-log-window 1
python3 - "$API" "$WADDR" >"$TMP/flood.out" 2>&1 <<'PY' || { cat "$TMP/flood.out"; fail "flood"; }
import socket, sys
api_host, api_port = sys.argv[1].rsplit(":", 1)
w_host, w_port = sys.argv[2].rsplit(":", 1)
codes = {}
for i in range(300):
    s = socket.create_connection((api_host, int(api_port)), timeout=10)
    s.sendall(b"GET /api/v1/jobs HTTP/1.1\r\nHost: x\r\nConnection: close\r\n"
              b"Authorization: Bearer not-the-token\r\n\r\n")
    code = s.recv(64).split(b" ")[1].decode()
    codes[code] = codes.get(code, 0) + 1
    s.close()
print("api", codes)
for i in range(50):
    s = socket.create_connection((w_host, int(w_port)), timeout=10)
    s.sendall(b"GET / HTTP/1.0\r\n\r\n" + b"x" * 64)
    try:
        while s.recv(4096):
            pass
    except OSError:
        pass
    s.close()
print("workers done")
PY
grep -q "api {'401': 300}" "$TMP/flood.out" || { cat "$TMP/flood.out"; fail "not 300 refusals"; }
[ "$(metric gi_farm_api_refused_auth_total)" = 300 ] || fail "the API's refusals are not all counted"
wait_log "$LOG" "more refusals from 127.0.0.1 in the last"
# The first names the peer and the reason.
first=$(grep -m 1 "refused" "$LOG")
echo "$first" | grep -q "api: refused GET /api/v1/jobs from 127.0.0.1:[0-9]*: wrong bearer token" ||
    fail "the first refusal is not logged in full: $first"
# Every refusal is in a line or a count (none twice), once the last
# window's summary is out: a second or so after the last refusal gi-farmd
# read, later on a busy machine (it may still be reading the flood when the
# client is done).
logged() {
    counted=$(sed -n 's/.* \([0-9]*\) more refusals from 127.0.0.1 .*/\1/p' "$LOG" |
        awk '{s += $1} END {print s + 0}')
    full=$(grep -v "more refusals" "$LOG" | grep -c "api: refused\|refused unauthenticated peer")
    echo $((counted + full))
}
t0=$(date +%s)
while [ "$(logged)" -lt 350 ] && [ $(($(date +%s) - t0)) -lt 30 ]; do sleep 0.1; done
n=$(logged)
[ "$n" -eq 350 ] || { cat "$LOG"; fail "$n refusals logged or counted, not 350"; }
lines=$(grep -c "refused\|refusals" "$LOG")
[ "$lines" -ge 2 ] && [ "$lines" -le 30 ] || { cat "$LOG"; fail "$lines log lines for 350 refusals"; }
last='more refusals from 127.0.0.1 .*(the last: refused unauthenticated peer (127.0.0.1:[0-9]*): '
grep -q "$last.*bad magic" "$LOG" ||
    { cat "$LOG"; fail "the summary does not say the last reason"; }
stop_farmd "$LOG"
