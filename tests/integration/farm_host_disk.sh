# A worker host whose batch disk is full: its failures are the host's, not
# the task's. The job does not fail (its attempts are not counted), the host
# is blocklisted, and a healthy host that joins later finishes the job with
# the same frames as `gi render`. `gi render` itself stops at once on a full
# disk (retrying on the same disk cannot help) and says why.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
need_own_disk 64k
mkdir -p "$TMP/full"

write_job "$TMP/job.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene-mobile.json", "method": "detp", "seed": 5,
 "image": {"width": 16, "height": 16},
 "detp": {"photons": 100000, "batch": 50000, "subdivide": 80, "tile": 16, "image_spp": 1,
          "animation": {"object": "mobile", "frames": 3,
                        "keyframes": [{"frame": 0, "translate": [340, -338.9, -90]},
                                      {"frame": 2, "translate": [320, -338.9, -70]}]}},
 "outputs": {"exr": "img.exr", "bin": "v.bin"}}
JOB
"$GI_RELEASE" render "$TMP/job.json" --workers 1 --out "$TMP/ref" --progress none >/dev/null 2>&1 ||
    fail "gi render"

# gi render with its batches on the full disk: one attempt, a clear error.
set +e
TMPDIR="$TMP/full" sh "$TMP/own_disk.sh" "$TMP/full" "$GI" render "$TMP/job.json" --workers 1 \
    --out "$TMP/local" --progress none >"$TMP/local.log" 2>&1
rc=$?
set -e
[ $rc -eq 1 ] || { cat "$TMP/local.log"; fail "gi render on a full disk: exit $rc"; }
grep -q "No space left on device; the photon batches are written under \$TMPDIR ($TMP/full): free space there or set TMPDIR to a larger disk" \
    "$TMP/local.log" || { cat "$TMP/local.log"; fail "no reason, no hint"; }
! grep -q "retrying task" "$TMP/local.log" || { cat "$TMP/local.log"; fail "retried on a full disk"; }

make_secrets
LOG="$TMP/farmd.log"
start_farmd "$TMP/state" "$LOG" -- --heartbeat 0.2 --lease 5 --dead 10 --blocklist-failures 3 \
    --max-attempts 2
start_worker "$TMP/full.log" sh "$TMP/own_disk.sh" "$TMP/full" -- --connect "$WADDR" --procs 1 \
    --cache "$TMP/c1" --batch-dir "$TMP/full" --name full
wait_workers 1
id=$("$GI" submit "$TMP/job.json" 2>/dev/null) || fail "submit"
wait_log "$LOG" "worker full blocklisted"
unended "$id" || { api "/api/v1/jobs/$id"; fail "the job did not wait for a host"; }
[ "$(jnum "$id" host_disk_errors)" -ge 3 ] || { api "/api/v1/jobs/$id"; fail "host disk errors"; }
[ "$(jnum "$id" retries)" = 0 ] || { api "/api/v1/jobs/$id"; fail "a full disk took attempts"; }
api "/api/v1/jobs/$id" | grep -q "No space left on device (that host's disk: not counted as an attempt)" ||
    { api "/api/v1/jobs/$id"; fail "the job's log does not say why"; }
start_worker "$TMP/good.log" -- --connect "$WADDR" --procs 1 --cache "$TMP/c2" --name good
wait_state "$id" done 120
"$GI" fetch "$id" --out "$TMP/out" >/dev/null || fail "fetch"
for f in 0000 0001 0002; do
    for k in img.$f.exr v.$f.bin; do
        cmp "$TMP/ref/$k" "$TMP/out/$k" || fail "$k differs from gi render"
    done
done
stop_farmd "$LOG"
echo ok
