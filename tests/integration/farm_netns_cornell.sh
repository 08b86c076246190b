# A Cornell box job on a coordinator host and three worker hosts (network
# namespaces joined by a bridge, each with its own address) gives a
# byte-identical EXR to `gi render --workers 1`. The client submits from the
# coordinator's host with `gi submit --wait`, which uploads the scene as an
# asset: no filesystem is shared with the farm.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
need_netns
write_job "$TMP/job.json" <<JOB
{
  "name": "cornell-netns",
  "scene": "$SRC/scenes/cornell-box/scene.json",
  "method": "pt",
  "seed": 11,
  "image": {"width": 64, "height": 48},
  "pt": {"spp": 32, "tile": 16, "pass_spp": 8},
  "outputs": {"exr": "cornell.exr", "png": "cornell.png"}
}
JOB
"$GI_RELEASE" render "$TMP/job.json" --workers 1 --out "$TMP/ref" --progress none >"$TMP/ref.log" 2>&1 ||
    { cat "$TMP/ref.log"; fail "reference render"; }
netns_farm "gic$$" --heartbeat 0.5 --lease 5 --dead 20
$FARM_EXEC "$GI" submit "$TMP/job.json" --wait --out "$TMP/farm" --progress none >"$TMP/submit.log" 2>&1 ||
    { cat "$TMP/submit.log" "$TMP/farmd.log"; fail "gi submit --wait"; }
cmp "$TMP/ref/cornell.exr" "$TMP/farm/cornell.exr" || fail "the farm's EXR differs from gi render's"
cmp "$TMP/ref/cornell.png" "$TMP/farm/cornell.png" || fail "the farm's PNG differs"

# Every worker host took part, each from its own address.
$FARM_EXEC "$GI" workers --json >"$TMP/workers.json" || fail "gi workers"
for i in 1 2 3; do
    a=$(sh "$NETNS" addr "$P" "w$i")
    grep -q "\"address\":[[:space:]]*\"$a:" "$TMP/workers.json" || { cat "$TMP/workers.json"; fail "host$i is not connected from $a"; }
done
done_counts=$(grep -o '"tasks_done":[[:space:]]*[0-9]*' "$TMP/workers.json" | grep -o '[0-9]*$' | tr '\n' ' ')
for n in $done_counts; do [ "$n" -gt 0 ] || fail "a worker host ran no task ($done_counts)"; done
[ "$(echo "$done_counts" | wc -w)" -eq 3 ] || fail "expected 3 workers, got: $done_counts"
# Each host fetched the scene once, into its own cache (beside the cache's lock).
for i in 1 2 3; do
    [ "$(find "$TMP/cache$i" -type f ! -name .lock | wc -l)" -eq 1 ] || fail "host$i's asset cache"
done
stop_farmd "$TMP/farmd.log"
echo "identical; tasks per host: $done_counts"
