# kill -9 of every process of a worker host in the middle of a job: the
# coordinator sees the connection drop, the tasks that host held fail and
# run again elsewhere, and the job completes with a byte-identical image.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
need_netns
make_secrets
P=gik$$
netns_up "$P" 3
C=$(sh "$NETNS" addr "$P" c)
FARM_EXEC="ip netns exec $P-c"
write_job "$TMP/job.json" <<JOB
{
  "scene": "$SRC/scenes/cornell-box/scene.json",
  "method": "pt",
  "seed": 5,
  "image": {"width": 96, "height": 96},
  "pt": {"spp": 384, "tile": 16, "pass_spp": 8},
  "outputs": {"exr": "img.exr"}
}
JOB
"$GI_RELEASE" render "$TMP/job.json" --workers 2 --out "$TMP/ref" --progress none >/dev/null 2>&1 ||
    fail "reference render"
start_farmd "$TMP/state" "$TMP/farmd.log" ip netns exec "$P-c" -- \
    --listen-workers "$C:7071" --listen-api "$C:7070" --heartbeat 0.5 --lease 5 --dead 20
for i in 1 2 3; do
    start_worker "$TMP/w$i.log" ip netns exec "$P-w$i" -- --connect "$C:7071" --procs 1 \
        --cache "$TMP/cache$i" --name "host$i"
done
id=$($FARM_EXEC "$GI" submit "$TMP/job.json" 2>"$TMP/submit.log") || { cat "$TMP/submit.log"; fail "submit"; }
# Mid-job: at least a tenth merged, far from done.
n=0
while :; do
    merged=$(jnum "$id" merged)
    total=$(jnum "$id" total)
    [ "${total:-0}" -gt 0 ] && [ "$merged" -ge $((total / 10)) ] && break
    n=$((n + 1))
    [ $n -lt 600 ] || fail "the job did not progress"
    sleep 0.05
done
[ "$(jstate "$id")" = running ] || fail "the job ended before the kill; make it longer"
pids=$(ip netns pids "$P-w2")
[ -n "$pids" ] || fail "no process on host2"
# shellcheck disable=SC2086
kill -9 $pids
echo "killed host2's processes ($(echo $pids | wc -w)) at $merged of $total tasks merged"
wait_state "$id" done 120
$FARM_EXEC "$GI" fetch "$id" --out "$TMP/farm" >/dev/null || fail "fetch"
cmp "$TMP/ref/img.exr" "$TMP/farm/img.exr" || fail "the image differs after a worker host was killed"
grep -q "dropped worker host2" "$TMP/farmd.log" || { cat "$TMP/farmd.log"; fail "the loss was not noticed"; }
api "/api/v1/jobs/$id" >"$TMP/job.json.out"
grep -q "host2 .*was lost" "$TMP/job.json.out" || { cat "$TMP/job.json.out"; fail "no task failed with host2's loss"; }
[ "$(jnum "$id" results_this_run)" -eq "$(jnum "$id" total)" ] || fail "results accepted != tasks"
stop_farmd "$TMP/farmd.log"
echo "identical after losing host2 (retries: $(jnum "$id" retries))"
