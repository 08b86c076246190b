# A worker host's link is cut (its bridge port down) for longer than the
# lease: the coordinator lets its leases expire and gives the tasks to the
# other hosts. When the link returns, the results the host computed in the
# dark arrive late and are discarded: every task is merged exactly once, and
# the image is byte-identical.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
need_netns
cornell_job "$TMP/job.json" 3 96 96 768
netns_farm "gil$$" --heartbeat 0.2 --lease 1 --dead 60
id=$($FARM_EXEC "$GI" submit "$TMP/job.json" 2>"$TMP/submit.log") || { cat "$TMP/submit.log"; fail "submit"; }
wait_merged "$id" 30
sh "$NETNS" cut "$P" w1
echo "cut host1 at $merged of $total tasks merged"
# Until its leases expired, however long a busy coordinator takes to see
# it (a fixed time could plug the link back first: no late result). (The
# others may finish the job meanwhile: host1's tasks can only complete by
# being given to them once its leases expire.)
wait_log "$TMP/farmd.log" "lease expired on worker host1"
sh "$NETNS" plug "$P" w1
wait_state "$id" done 120
# The late results come with TCP's retransmissions after the link is back.
n=0
while [ "$(metric gi_farm_late_results_total)" = 0 ]; do
    n=$((n + 1))
    [ $n -lt 300 ] || { grep -i "lease\|late" "$TMP/farmd.log"; fail "no late result arrived"; }
    sleep 0.1
done
late=$(metric gi_farm_late_results_total)
expired=$(metric gi_farm_lease_expiries_total)
[ "$expired" -ge 1 ] || fail "no lease expired"
grep -q "lease expired on worker host1" "$TMP/farmd.log" || fail "no expiry logged for host1"
grep -q "discarding a late result for job $id .* from worker host1" "$TMP/farmd.log" ||
    fail "no late result from host1 logged"
# Exactly one accepted (merged) result per task: none counted twice.
[ "$(jnum "$id" results_this_run)" -eq "$(jnum "$id" total)" ] || fail "results accepted != tasks"
[ "$(jnum "$id" merged)" -eq "$(jnum "$id" total)" ] || fail "merged != tasks"
$FARM_EXEC "$GI" fetch "$id" --out "$TMP/farm" >/dev/null || fail "fetch"
cmp "$TMP/job.json.ref/img.exr" "$TMP/farm/img.exr" || fail "the image differs after the link cut"
# host1 was never dropped (the cut was shorter than --dead) and works again.
grep -q "dropped worker host1" "$TMP/farmd.log" && fail "host1 was dropped"
stop_farmd "$TMP/farmd.log"
echo "identical; $expired leases expired, $late late results discarded"
