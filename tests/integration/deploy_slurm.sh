# deploy/slurm/gi-workers.sbatch under a stand-in srun that runs the step as
# two "nodes" on this machine, with the variables Slurm sets: both workers
# join under their node names, a job renders to the same bytes as gi render,
# and SIGTERM to the step's tasks (Slurm ending the job) drains them: the
# script exits 0 and the per-job caches are gone. Without a coordinator
# address it refuses to start.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
command -v bash >/dev/null || skip "bash is not installed"
SBATCH="$SRC/deploy/slurm/gi-workers.sbatch"
set +e
env -u GI_FARM_COORDINATOR bash "$SBATCH" >/dev/null 2>"$TMP/noaddr.err"
rc=$?
set -e
[ $rc -ne 0 ] && grep -q "GI_FARM_COORDINATOR" "$TMP/noaddr.err" ||
    { cat "$TMP/noaddr.err"; fail "no coordinator address: exit $rc"; }

make_secrets
cornell_job "$TMP/pt.json" 5 32 32 16
start_farmd "$TMP/state" "$TMP/farmd.log" -- --heartbeat 0.2 --lease 5 --dead 20
mkdir -p "$TMP/bin" "$TMP/nodes"
cat >"$TMP/bin/srun" <<'SRUN'
#!/bin/bash
# srun's stand-in: the step's command once per node (FAKE_NODES), each with
# the task variables Slurm sets; SIGTERM goes on to every task.
while [ $# -gt 0 ] && [ "${1#--}" != "$1" ]; do shift; done
pids=()
for ((i = 0; i < FAKE_NODES; i++)); do
    SLURM_NODEID=$i SLURM_PROCID=$i SLURMD_NODENAME=node$i "$@" &
    pids+=($!)
done
trap 'kill -TERM "${pids[@]}" 2>/dev/null' TERM
status=0
for p in "${pids[@]}"; do
    while :; do
        wait "$p"
        s=$?
        kill -0 "$p" 2>/dev/null || break
    done
    [ "$s" -eq 0 ] || status=$s
done
exit "$status"
SRUN
chmod +x "$TMP/bin/srun"
PATH="$TMP/bin:$PATH" FAKE_NODES=2 SLURM_JOB_ID=4242 GI_FARM_COORDINATOR="$WADDR" \
    GI_WORKER="$WORKER" GI_WORKER_PROCS=1 TMPDIR="$TMP/nodes" \
    bash "$SBATCH" >"$TMP/sbatch.log" 2>&1 &
SB=$!
FARM_PIDS="$FARM_PIDS $SB"
show_on_failure "$TMP/sbatch.log"
wait_workers 2
"$GI" workers >"$TMP/workers.txt"
for n in node0 node1; do
    grep -q "$n-slurm4242" "$TMP/workers.txt" || { cat "$TMP/workers.txt"; fail "no worker $n"; }
done
[ -d "$TMP/nodes/gi-worker-4242-node0" ] || fail "no per-job cache for node0"
"$GI" submit "$TMP/pt.json" --wait --out "$TMP/farm" --progress none >"$TMP/submit.log" 2>&1 ||
    { cat "$TMP/submit.log"; fail "the job did not render"; }
cmp "$TMP/pt.json.ref/img.exr" "$TMP/farm/img.exr" || fail "the farm's image differs from gi render"

pkill -TERM -f "$TMP/bin/srun" || fail "no srun to signal"
wait "$SB" || fail "the batch script exited with status $? after SIGTERM"
[ "$(grep -c "is draining" "$TMP/farmd.log")" -eq 2 ] || fail "the workers did not drain"
[ -z "$(ls -A "$TMP/nodes")" ] || { ls -la "$TMP/nodes"; fail "per-job caches left behind"; }
echo ok
