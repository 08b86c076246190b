# Retention: gi-farmd purges ended jobs by itself, exactly as `gi purge`
# does (journaled, files removed), logging why. --keep-ended-bytes sends
# the oldest ended jobs first while the ended jobs' files hold more (those
# fetched before those never fetched: at the end);
# --keep-ended purges a job that long after it ended, counted from its
# journaled end, so a job due while gi-farmd was stopped goes at its
# restart. A job not ended is never purged; `gi status` says when an ended
# one will be.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
LOG="$TMP/farmd.log"
STATE="$TMP/state"
job() { # job FILE SEED
    write_job "$1" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "pt", "seed": $2,
 "image": {"width": 16, "height": 16}, "pt": {"spp": 8, "tile": 16, "pass_spp": 8},
 "outputs": {"exr": "img.exr"}}
JOB
}
job "$TMP/a.json" 1
job "$TMP/b.json" 2
gone() { # gone ID: 404 from the API, its directory removed
    code=$(api "/api/v1/jobs/$1" -o /dev/null -w '%{http_code}')
    [ "$code" = 404 ] || fail "job $1 is still there (HTTP $code)"
    [ ! -e "$STATE/jobs/$1" ] || fail "job $1's directory is still there"
}
kept() { # kept ID STATE
    [ "$(jstate "$1")" = "$2" ] || fail "job $1 is not $2 any more: $(jstate "$1")"
}

# Without retention (the default): jobs 1 and 2 done, 3 cancelled; kept.
start_farmd "$STATE" "$LOG"
start_worker "$TMP/worker.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/cache"
for f in a b; do
    "$GI" submit "$TMP/$f.json" --wait --out "$TMP/out-$f" --progress none >"$TMP/submit-$f.log" 2>&1 ||
        { cat "$TMP/submit-$f.log"; fail "submit $f"; }
done
kill "$WORKER_PID"; wait "$WORKER_PID" 2>/dev/null || true
id3=$("$GI" submit "$TMP/a.json" 2>/dev/null) || fail "submit 3"
"$GI" cancel "$id3" >/dev/null || fail "cancel 3"
"$GI" status 1 | grep -q "purged at" && fail "a purge time shown without --keep-ended"
api /api/v1/jobs/1 | grep -q '"purge_at":null' || fail "purge_at is not null without --keep-ended"
stop_farmd "$LOG"
t_ended=$(date +%s)

# --keep-ended 1h: nothing is due yet; status says when each will be.
start_farmd "$STATE" "$LOG" -- --keep-ended 1h
"$GI" status 1 >"$TMP/status" || fail "gi status 1"
grep -q "purged at 20.*Z by the farm's retention" "$TMP/status" || { cat "$TMP/status"; fail "no purge time"; }
ended=$(api /api/v1/jobs/1 | grep -o '"ended":"[^"]*"' | cut -d'"' -f4)
at=$(api /api/v1/jobs/1 | grep -o '"purge_at":"[^"]*"' | cut -d'"' -f4)
[ $(($(date -d "$at" +%s) - $(date -d "$ended" +%s))) -eq 3600 ] || fail "purge_at $at, ended $ended"
sleep 1.5 # a retention pass or more
kept 1 done; kept 2 done; kept "$id3" cancelled
stop_farmd "$LOG"

# --keep-ended-bytes one byte under what the three hold: the oldest ended
# (job 1) goes, and only it.
sizes=$(for i in 1 2 "$id3"; do [ -e "$STATE/jobs/$i" ] && du -sB1 "$STATE/jobs/$i" | cut -f1 || echo 0; done)
total=$(echo "$sizes" | awk '{s += $1} END {print s}')
[ "$total" -gt 1 ] || fail "the jobs' directories hold $total bytes"
start_farmd "$STATE" "$LOG" -- --keep-ended-bytes $((total - 1))
wait_log "$LOG" "job 1 (.*, done): purged by retention: the ended jobs' files hold $total bytes"
gone 1
sleep 1.5
kept 2 done; kept "$id3" cancelled
stop_farmd "$LOG"

# --keep-ended 3: jobs 2 and 3 ended more than 3 s ago, while gi-farmd
# was stopped: purged at its start. A job that ends now is kept 3 s (its
# outputs are fetched), then purged; one not ended stays.
while [ $(($(date +%s) - t_ended)) -le 3 ]; do sleep 0.2; done
start_farmd "$STATE" "$LOG" -- --keep-ended 3
wait_log "$LOG" "job 2 (.*, done): purged by retention: ended .* ago (--keep-ended 3.0s)"
wait_log "$LOG" "job $id3 (.*, cancelled): purged by retention"
gone 2; gone "$id3"
start_worker "$TMP/worker.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/cache"
"$GI" submit "$TMP/b.json" --wait --out "$TMP/out-4" --progress none >"$TMP/submit-4.log" 2>&1 ||
    { cat "$TMP/submit-4.log"; fail "submit 4"; }
id4=$(sed -n 's/.*submitted .* as job \([0-9]*\).*/\1/p' "$TMP/submit-4.log")
cmp "$TMP/out-b/img.exr" "$TMP/out-4/img.exr" || fail "job $id4's outputs"
kill "$WORKER_PID"; wait "$WORKER_PID" 2>/dev/null || true
id5=$("$GI" submit "$TMP/a.json" 2>/dev/null) || fail "submit 5"
wait_log "$LOG" "job $id4 (.*, done): purged by retention: ended [0-9.]*s ago (--keep-ended 3.0s)"
gone "$id4"
grep -q "job $id4 purged: " "$LOG" || fail "not the purge's own path"
sleep 3.5
st=$(jstate "$id5")
[ "$st" = running ] || [ "$st" = checking ] || fail "job $id5, not ended, is $st"
stop_farmd "$LOG"

# The purges are journaled: a restart without retention knows only job 5.
start_farmd "$STATE" "$LOG"
[ "$("$GI" jobs | awk 'NR > 1 {print $1}' | tr '\n' ' ')" = "$id5 " ] ||
    { "$GI" jobs; fail "purged jobs are back after a restart"; }
"$GI" cancel "$id5" >/dev/null
stop_farmd "$LOG"

# Fetched first: an output of a done job sent whole through the API (gi
# fetch, gi wait) is journaled (FETCHED) and shown (fetched, gi status);
# HEAD is not a fetch. Retention purges the jobs fetched, or failed or
# cancelled (no outputs), before the done jobs never fetched, the oldest
# first within each, and warns when it purges one never fetched.
STATE="$TMP/state3"
LOG="$TMP/farmd3.log"
start_farmd "$STATE" "$LOG"
start_worker "$TMP/worker.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/cache"
for i in 1 2 3; do
    job "$TMP/f$i.json" $((10 + i))
    [ "$("$GI" submit "$TMP/f$i.json" 2>/dev/null)" = $i ] || fail "submit f$i"
    wait_state $i done 120
done
kill "$WORKER_PID"; wait "$WORKER_PID" 2>/dev/null || true
api /api/v1/jobs/1/outputs/img.exr -o /dev/null -I || fail "HEAD of job 1's output"
"$GI" fetch 2 --out "$TMP/fetched" >/dev/null || fail "gi fetch 2"
"$GI" fetch 2 --out "$TMP/fetched" >/dev/null || fail "gi fetch 2 again"
cmp -s "$TMP/fetched/img.exr" "$STATE/jobs/2/out/img.exr" || fail "job 2's output fetched"
wait_log "$LOG" 'job 2: outputs fetched: "img.exr" sent whole to '
[ "$(grep -c "job 2: outputs fetched" "$LOG")" = 1 ] || fail "the second fetch logged again"
fetched() { api "/api/v1/jobs/$1" | grep -o '"fetched":[^,]*' | cut -d: -f2-; }
for n in 1 2; do # as fetched, then from the journal (and the compacted one)
    case $(fetched 2) in '"20'*Z'"') ;; *) api /api/v1/jobs/2; fail "job 2 not fetched ($n)" ;; esac
    [ "$(fetched 1)" = null ] && [ "$(fetched 3)" = null ] || fail "jobs 1, 3 fetched ($n)"
    "$GI" status 2 | grep -q "outputs fetched at 20" || { "$GI" status 2; fail "gi status 2"; }
    "$GI" status 1 | grep -q "outputs never fetched (gi fetch 1)" ||
        { "$GI" status 1; fail "gi status 1"; }
    stop_farmd "$LOG"
    start_farmd "$STATE" "$LOG"
done
stop_farmd "$LOG"
sizes() { # bytes of the jobs' directories
    for i in "$@"; do du -sB1 "$STATE/jobs/$i" | cut -f1; done | awk '{s += $1} END {print s}'
}
# One byte over: job 2 goes (fetched), not job 1 (older, never fetched).
total=$(sizes 1 2 3)
start_farmd "$STATE" "$LOG" -- --keep-ended-bytes $((total - 1))
wait_log "$LOG" "job 2 (.*, done): purged by retention: .*, and it is the oldest fetched or without"
gone 2
sleep 1.5
kept 1 done; kept 3 done
! grep -q "never fetched" "$LOG" || fail "a warning for a fetched job"
stop_farmd "$LOG"
# Over again: none fetched is left, job 1 (the oldest) goes, with a warning.
total=$(sizes 1 3)
start_farmd "$STATE" "$LOG" -- --keep-ended-bytes $((total - 1))
wait_log "$LOG" "warning.*job 1 (.*, done): purged by retention: .*; its outputs were never fetched"
gone 1
sleep 1.5
kept 3 done
stop_farmd "$LOG"

# Bad values are refused, naming the option.
st=0
"$FARMD" --state "$TMP/s2" --keep-ended 0 >"$TMP/bad.log" 2>&1 || st=$?
[ $st -eq 2 ] && grep -q -- '--keep-ended: "0" is not a duration' "$TMP/bad.log" ||
    { cat "$TMP/bad.log"; fail "--keep-ended 0: exit $st"; }
st=0
"$FARMD" --state "$TMP/s2" --keep-ended 3x >"$TMP/bad.log" 2>&1 || st=$?
[ $st -eq 2 ] || fail "--keep-ended 3x: exit $st"
