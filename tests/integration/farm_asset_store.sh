# The coordinator's asset store shrinks: a purged job's uploads go with it
# unless another job names the same bytes (or they were uploaded or named
# too recently: a job may be on its way), and data a job published for its
# tasks goes when the job is done. (And a method's warnings reach the job's
# log.)
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
LOG="$TMP/farmd.log"
start_farmd "$TMP/state" "$LOG" -- --heartbeat 0.2 --lease 3 --dead 10 --checkpoint 0.1
start_worker "$TMP/w.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/cache"
# A copy of the Cornell box of its own, so its bytes are this test's.
cp "$SRC/scenes/cornell-box/scene.json" "$TMP/scene.json"
write_job "$TMP/pt.json" <<JOB
{"scene": "scene.json", "method": "pt", "seed": 3, "image": {"width": 16, "height": 16},
 "pt": {"spp": 8, "tile": 16, "pass_spp": 8}, "outputs": {"exr": "img.exr"}}
JOB
# detp with an image: its tiles read the per-vertex radiance it publishes.
write_job "$TMP/detp.json" <<JOB
{"scene": "scene.json", "method": "detp", "seed": 3, "image": {"width": 192, "height": 192},
 "detp": {"photons": 200000, "batch": 20000, "subdivide": 60, "tile": 8, "image_spp": 16},
 "outputs": {"exr": "img.exr"}}
JOB
# run JOB: submits it, waits for it to be done, prints its id.
run() {
    id=$("$GI" submit "$1" 2>/dev/null) || fail "submit $1"
    wait_state "$id" done 120
    echo "$id"
}
store_files() { find "$TMP/state/assets" -type f ! -path "$TMP/state/assets/tmp/*" | wc -l; }
backdate() { find "$TMP/state/assets" -type f -exec touch -d '2 hours ago' {} +; }

a=$(run "$TMP/pt.json")
b=$(run "$TMP/detp.json")
# A method's warning about a job reaches the job's log (detp's coarse discs).
api "/api/v1/jobs/$b" | grep -q "warning: detp: detp: the discs' radius is .*: a coarse bake" ||
    { api "/api/v1/jobs/$b"; fail "the method's warning is not in the job's log"; }
# The scene is the only upload (both jobs name it); b's published data is gone.
[ "$(store_files)" = 1 ] || { find "$TMP/state/assets" -type f; fail "store after two jobs"; }
bytes=$(metric gi_farm_asset_store_bytes)
[ "$bytes" = "$(wc -c <"$TMP/scene.json")" ] || fail "store bytes $bytes"

backdate
"$GI" purge "$a" >/dev/null || fail "purge a"
[ "$(store_files)" = 1 ] || fail "the scene went with a while b names it"
"$GI" purge "$b" >/dev/null || fail "purge b"
[ "$(store_files)" = 0 ] || { find "$TMP/state/assets" -type f; fail "the scene stayed"; }
[ "$(metric gi_farm_asset_store_bytes)" = 0 ] || fail "store bytes after the purges"
grep -q "job $b purged: [1-9][0-9]* bytes of the asset store freed" "$LOG" || fail "not logged"

# Within the grace period a purged job's upload stays (a submission on its
# way may name it), and is reused by the next job.
c=$(run "$TMP/pt.json")
"$GI" purge "$c" >/dev/null || fail "purge c"
[ "$(store_files)" = 1 ] || fail "a fresh upload went at once"
run "$TMP/pt.json" >/dev/null
stop_farmd "$LOG"
echo ok
