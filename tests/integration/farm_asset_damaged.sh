# A file damaged in the coordinator's asset store (its bytes no longer hash
# to its name) is caught when read: the job fails at once with an error that
# names the asset and its path, instead of workers refusing the bytes,
# reconnecting in a loop and the job failing for a reason that names nothing.
# The damaged file is moved aside, so submitting the job again uploads the
# bytes anew and renders.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
LOG="$TMP/farmd.log"
start_farmd "$TMP/state" "$LOG" -- --heartbeat 0.2 --lease 3 --dead 10
cp "$SRC/scenes/cornell-box/scene.json" "$TMP/scene.json"
write_job "$TMP/pt.json" <<JOB
{"scene": "scene.json", "method": "pt", "seed": 3, "image": {"width": 16, "height": 16},
 "pt": {"spp": 8, "tile": 16, "pass_spp": 8}, "outputs": {"exr": "img.exr"}}
JOB
# Submitted with no worker: checked and queued, its scene in the store.
id=$("$GI" submit "$TMP/pt.json" 2>/dev/null) || fail "submit"
wait_state "$id" running 30
h=$(b2sum -l 256 "$TMP/scene.json" | cut -d' ' -f1)
stored="$TMP/state/assets/$(echo "$h" | cut -c1-2)/$h"
[ -f "$stored" ] || fail "the scene is not at $stored"
printf 'X' | dd of="$stored" bs=1 seek=10 conv=notrunc 2>/dev/null
start_worker "$TMP/w.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/cache"
wait_state "$id" failed 60
api "/api/v1/jobs/$id" >"$TMP/job.txt"
grep -q "asset store: $h is damaged ($stored" "$TMP/job.txt" ||
    { cat "$TMP/job.txt"; fail "the job's error does not name the damaged asset"; }
aside="$TMP/state/assets/damaged/$h"
grep -q "it was moved to $aside" "$TMP/job.txt" ||
    { cat "$TMP/job.txt"; fail "the job's error does not say where the file went"; }
[ -f "$aside" ] && [ ! -e "$stored" ] || fail "the damaged file was not moved to $aside"
# No worker was blamed for it.
! grep -q "blocklisted" "$LOG" || fail "a worker was blocklisted"
# Submitted again, the scene is uploaded anew and the job renders.
id2=$("$GI" submit "$TMP/pt.json" 2>"$TMP/submit2.err") || { cat "$TMP/submit2.err"; fail "resubmit"; }
wait_state "$id2" done 60
cmp -s "$stored" "$TMP/scene.json" || fail "the store does not hold the scene's bytes again"
stop_farmd "$LOG"
echo ok
