# kill -9 of every process of a worker host in the middle of a job: the
# coordinator sees the connection drop, the tasks that host held fail and
# run again elsewhere, and the job completes with a byte-identical image.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
need_netns
cornell_job "$TMP/job.json" 5 96 96 384 64
netns_farm "gik$$" --heartbeat 0.5 --lease 5 --dead 20
id=$($FARM_EXEC "$GI" submit "$TMP/job.json" 2>"$TMP/submit.log") || { cat "$TMP/submit.log"; fail "submit"; }
wait_merged "$id" 10
# Kill it while it holds a lease (on a loaded machine it can be between tasks;
# tasks of 64 spp a pass keep it inside one most of the time).
n=0
until [ "$(api /api/v1/workers | tr '{' '\n' | grep '"name":"host2"' |
    sed -n 's/.*"tasks_leased":\([0-9]*\).*/\1/p')" -gt 0 ] 2>/dev/null; do
    n=$((n + 1))
    [ $n -lt 200 ] || fail "host2 never held a lease"
    sleep 0.02
done
pids=$(ip netns pids "$P-w2")
[ -n "$pids" ] || fail "no process on host2"
# shellcheck disable=SC2086
kill -9 $pids
echo "killed host2's processes ($(echo $pids | wc -w)) at $merged of $total tasks merged"
wait_state "$id" done 120
$FARM_EXEC "$GI" fetch "$id" --out "$TMP/farm" >/dev/null || fail "fetch"
cmp "$TMP/job.json.ref/img.exr" "$TMP/farm/img.exr" || fail "the image differs after a worker host was killed"
grep -q "dropped worker host2" "$TMP/farmd.log" || { cat "$TMP/farmd.log"; fail "the loss was not noticed"; }
api "/api/v1/jobs/$id" | grep -q "host2 .*was lost" || fail "no task failed with host2's loss"
[ "$(jnum "$id" results_this_run)" -eq "$(jnum "$id" total)" ] || fail "results accepted != tasks"
stop_farmd "$TMP/farmd.log"
echo "identical after losing host2 (retries: $(jnum "$id" retries))"
