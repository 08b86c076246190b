# The farm's operations through `gi` and plain HTTP (curl): submit, status,
# jobs, workers, fetch, cancel, priorities, a worker's drain on SIGTERM, the
# metrics and dashboard endpoints, and local validation before anything is
# sent.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
LOG="$TMP/farmd.log"
start_farmd "$TMP/state" "$LOG" -- --heartbeat 0.2 --lease 3 --dead 10
job() { # NAME SEED SPP [SIZE]
    write_job "$TMP/$1.json" <<JOB
{"name": "$1", "scene": "$SRC/scenes/cornell-box/scene.json", "method": "pt", "seed": $2,
 "image": {"width": ${4:-32}, "height": ${4:-32}}, "pt": {"spp": $3, "tile": 16, "pass_spp": 16},
 "outputs": {"exr": "$1.exr"}}
JOB
}

# A bad job is refused by gi itself (exit 2), nothing reaches the farm.
printf '{"scene": "%s", "method": "pt", "pt": {"spp": 0}}' "$SRC/scenes/cornell-box/scene.json" >"$TMP/bad.json"
set +e
"$GI" submit "$TMP/bad.json" >/dev/null 2>"$TMP/bad.log"
rc=$?
set -e
[ $rc -eq 2 ] || fail "bad job: exit $rc"
grep -q "pt.spp" "$TMP/bad.log" || { cat "$TMP/bad.log"; fail "no reason"; }
[ "$(metric gi_farm_jobs_submitted_total)" = 0 ] || fail "the bad job reached the farm"
# So is one whose outputs, fetched into --out, would replace the job file.
printf '{"scene": "%s", "method": "pt", "outputs": {"exr": "self.json"}}' \
    "$SRC/scenes/cornell-box/scene.json" >"$TMP/self.json"
cp "$TMP/self.json" "$TMP/self.orig"
set +e
"$GI" submit "$TMP/self.json" --wait --out "$TMP" >/dev/null 2>"$TMP/self.log"
rc=$?
set -e
[ $rc -eq 2 ] && grep -q "outputs.exr: $TMP/self.json would replace one of the job's own files" \
    "$TMP/self.log" || { cat "$TMP/self.log"; fail "an output replacing its job: exit $rc"; }
cmp -s "$TMP/self.json" "$TMP/self.orig" || fail "the job file changed"
[ "$(metric gi_farm_jobs_submitted_total)" = 0 ] || fail "the self-replacing job reached the farm"

# Priorities: with no worker yet, queue a low (1) and a high (9) priority job
# of the same size; one single-process worker then runs the high one ~9x
# as often, so it ends while the low one is far from done.
job low 1 256 64
job high 2 256 64
lo=$("$GI" submit "$TMP/low.json" --priority 1 2>/dev/null) || fail "submit low"
hi=$("$GI" submit "$TMP/high.json" --priority 9 2>/dev/null) || fail "submit high"
"$GI" jobs >"$TMP/jobs.txt" || fail "gi jobs"
grep -q "^$hi .*running .* 9 .*high" "$TMP/jobs.txt" || { cat "$TMP/jobs.txt"; fail "gi jobs listing"; }
start_worker "$TMP/w1.log" -- --connect "$WADDR" --procs 1 --queue 0 --cache "$TMP/cache1" --name one
wait_state "$hi" done 60
lo_merged=$(jnum "$lo" merged)
lo_total=$(jnum "$lo" total)
echo "when the priority 9 job ended, the priority 1 job had $lo_merged of $lo_total tasks merged"
[ "$lo_merged" -lt $((lo_total / 3)) ] || fail "priorities not honoured ($lo_merged of $lo_total)"
wait_state "$lo" done 60
"$GI" fetch "$hi" --out "$TMP/fetched" >/dev/null || fail "gi fetch"
"$GI_RELEASE" render "$TMP/high.json" --workers 1 --out "$TMP/ref" --progress none >/dev/null 2>&1
cmp "$TMP/ref/high.exr" "$TMP/fetched/high.exr" || fail "fetched image differs"

# Plain HTTP.
api "/api/v1/jobs/$hi/outputs/high.exr" -o "$TMP/curl.exr"
cmp "$TMP/ref/high.exr" "$TMP/curl.exr" || fail "curl download differs"
[ "$(api "/api/v1/jobs/$hi/outputs/nope.exr" -o /dev/null -w '%{http_code}')" = 404 ] || fail "unknown output"
[ "$(api "/api/v1/jobs/999" -o /dev/null -w '%{http_code}')" = 404 ] || fail "unknown job"
# gi says which farm has no such job (another $GI_FARM?) and where the ids are.
set +e
"$GI" status 999 2>"$TMP/nojob.log"
rc=$?
set -e
[ $rc -eq 1 ] && grep -qF "no job 999 (HTTP 404 from the farm at ${GI_FARM#http://}; \`gi jobs\` lists" \
    "$TMP/nojob.log" || { cat "$TMP/nojob.log"; fail "gi status of an unknown job: $rc"; }
curl -s "$GI_FARM/" | grep -q "<title>gi-farm</title>" || fail "dashboard"
h=$(b2sum -l 256 "$SRC/scenes/cornell-box/scene.json" | cut -d' ' -f1)
[ "$(api "/api/v1/assets/$h" -o /dev/null -I -w '%{http_code}')" = 200 ] || fail "HEAD of an uploaded asset"
# A job posted with curl as a JSON object (numbers printed back exactly)
# renders the same bits as `gi render` of the file.
body=$(printf '{"job": %s, "assets": {"%s": "%s"}, "priority": 3}' "$(cat "$TMP/high.json")" \
    "$SRC/scenes/cornell-box/scene.json" "$h")
cid=$(api /api/v1/jobs -X POST --data-binary "$body" | grep -o '"id":[0-9]*' | cut -d: -f2)
[ -n "$cid" ] || fail "curl submission"
wait_state "$cid" done 60
api "/api/v1/jobs/$cid/outputs/high.exr" -o "$TMP/curl2.exr"
cmp "$TMP/ref/high.exr" "$TMP/curl2.exr" || fail "a job posted as an object renders differently"
api /metrics | grep -q '^gi_farm_jobs{state="done"} 3$' || { api /metrics; fail "metrics"; }
"$GI" status "$hi" | grep -q "tasks: 256 total, 256 merged" || { "$GI" status "$hi"; fail "gi status"; }
"$GI" workers | grep -q "^one .*active" || { "$GI" workers; fail "gi workers"; }

# Cancel a running job; the worker drops its tasks; the farm goes on.
job long 3 4096
id=$("$GI" submit "$TMP/long.json" 2>/dev/null) || fail "submit long"
wait_state "$id" running 30
n=0
while [ "$(jnum "$id" merged)" -lt 4 ]; do n=$((n + 1)); [ $n -lt 300 ] || fail "no progress"; sleep 0.05; done
# Batch files of this job id left by an earlier run of the worker (another
# job text, hence another hash) go with it too.
mkdir -p "$TMP/cache1/batches/$id-0123456789abcdef" "$TMP/cache1/batches/${id}0-0123456789abcdef"
: >"$TMP/cache1/batches/$id-0123456789abcdef/b0.f0"
"$GI" cancel "$id" | grep -q "job $id cancelled" || fail "gi cancel"
[ "$(jstate "$id")" = cancelled ] || fail "not cancelled"
wait_log "$TMP/w1.log" "job $id is over"
[ ! -e "$TMP/cache1/batches/$id-0123456789abcdef" ] || fail "an earlier run's batch files of job $id stay"
[ -d "$TMP/cache1/batches/${id}0-0123456789abcdef" ] || fail "job ${id}0's batch directory was removed"
set +e
"$GI" wait "$id" --progress none >/dev/null 2>"$TMP/wait.log"
rc=$?
set -e
[ $rc -eq 1 ] && grep -q "^gi: job $id cancelled: requested through the API; .gi retry $id. runs it" \
    "$TMP/wait.log" || { cat "$TMP/wait.log"; fail "gi wait on a cancelled job: $rc"; }
# gi fetch of it says it has no outputs and what to do instead.
set +e
"$GI" fetch "$id" --out "$TMP/none" >/dev/null 2>"$TMP/fetch.log"
rc=$?
set -e
want="job $id is cancelled, not done: it has no outputs (\`gi status $id\` says why; \`gi retry $id"
[ $rc -eq 1 ] && grep -qF "$want --wait\` runs it again" "$TMP/fetch.log" ||
    { cat "$TMP/fetch.log"; fail "gi fetch of a cancelled job: $rc"; }
# JSON progress: outputs fetched and the end, or the state it ended in.
"$GI" wait "$hi" --out "$TMP/fetched2" --progress json >/dev/null 2>"$TMP/wait.json" || fail "gi wait done job"
grep -q '^{"event":"output","job":"high","kind":"exr","path":"'"$TMP"'/fetched2/high.exr"}$' "$TMP/wait.json" &&
    tail -n 1 "$TMP/wait.json" | grep -q '^{"event":"end","job":"high","state":"done","elapsed_s":[0-9.]*}$' ||
    { cat "$TMP/wait.json"; fail "gi wait --progress json of a done job"; }
set +e
"$GI" wait "$id" --progress json >/dev/null 2>"$TMP/wait.json"
set -e
tail -n 1 "$TMP/wait.json" | grep -q '^{"event":"end","job":"long","state":"cancelled",.*"error":' ||
    { cat "$TMP/wait.json"; fail "gi wait --progress json of a cancelled job"; }
# Cancelling an ended job changes nothing (a cancel run twice keeps the
# outputs); purging removes it.
set +e
"$GI" cancel "$lo" >/dev/null 2>"$TMP/cancel.log"
rc=$?
set -e
[ $rc -eq 1 ] && grep -q "has ended (done): .gi purge $lo. (DELETE /api/v1/jobs/$lo?purge=1) removes it" "$TMP/cancel.log" ||
    { cat "$TMP/cancel.log"; fail "gi cancel of an ended job: exit $rc"; }
[ "$(jstate "$lo")" = done ] || fail "gi cancel changed an ended job"
[ "$(api "/api/v1/jobs/$lo?purge=yes" -X DELETE -o /dev/null -w '%{http_code}')" = 400 ] ||
    fail "purge=yes was not refused"
"$GI" purge "$lo" | grep -q "removed" || fail "gi purge of an ended job"
# %00 in a path is not a NUL that cuts it short.
[ "$(api "/api/v1/jobs/$hi%00x" -o /dev/null -w '%{http_code}')" = 404 ] || fail "/jobs/$hi%00x was served"
[ "$(api "/api/v1/jobs/$hi/outputs/high.exr%00.x" -o /dev/null -w '%{http_code}')" = 404 ] ||
    fail "an output name with %00 was served"
[ "$(api "/api/v1/jobs/$lo" -o /dev/null -w '%{http_code}')" = 404 ] || fail "removed job still listed"

# Drain: a second worker gets SIGTERM in the middle of a job; it hands its
# queued tasks back, finishes its running one, says goodbye and exits 0.
start_worker "$TMP/w2.log" -- --connect "$WADDR" --procs 1 --queue 3 --cache "$TMP/cache2" --name two
job mid 4 256
id=$("$GI" submit "$TMP/mid.json" 2>/dev/null) || fail "submit mid"
n=0
while [ "$(jnum "$id" merged)" -lt 8 ]; do n=$((n + 1)); [ $n -lt 300 ] || fail "no progress"; sleep 0.05; done
kill -TERM "$WORKER_PID"
wait "$WORKER_PID" || { cat "$TMP/w2.log"; fail "the draining worker exited with $?"; }
grep -q "draining" "$TMP/w2.log" || fail "no drain"
wait_log "$LOG" "worker two (.*) is draining"
wait_log "$LOG" "worker two (.*) left: said goodbye"
wait_state "$id" done 60
"$GI" fetch "$id" --out "$TMP/fetched" >/dev/null
"$GI_RELEASE" render "$TMP/mid.json" --workers 1 --out "$TMP/ref" --progress none >/dev/null 2>&1
cmp "$TMP/ref/mid.exr" "$TMP/fetched/mid.exr" || fail "image differs after a drain"
[ "$(jnum "$id" retries)" = 0 ] || fail "a drain counted as a failure"
stop_farmd "$LOG"
echo ok
