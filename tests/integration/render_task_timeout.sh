# Task time limits in `gi render`: a task that hangs (GI_FAULT_HANG_TASK:
# its pool child sleeps instead of running it) is stopped after the job's
# task_timeout (or --task-timeout when the job sets none): the child is
# killed and replaced, the run fails as an attempt, and the retry finishes
# the render with the image of an undisturbed one; a task that hangs on
# every run fails the render with the timeout after its attempts. Tasks
# waiting for a free child are off the clock. Bad limits are refused naming
# the flag or the field. `timeout` turns a render that would wait forever
# into a failure.
. "$(dirname "$0")/lib.sh"
write_job "$TMP/job.json" <<JOB
{
  "scene": "$SRC/scenes/cornell-box/scene.json",
  "method": "pt",
  "seed": 8,
  "task_timeout": 2,
  "image": {"width": 32, "height": 32},
  "pt": {"spp": 32, "tile": 16, "pass_spp": 8},
  "outputs": {"exr": "img.exr"}
}
JOB
sed '/"task_timeout"/d' "$TMP/job.json" >"$TMP/plain.json"
"$GI" render "$TMP/job.json" --workers 2 --out "$TMP/ref" --progress none >/dev/null 2>&1 ||
    fail "reference render"

# 1. The job's limit: task 2 hangs on its first run only.
GI_FAULT_HANG_TASK=2:0 timeout 120 "$GI" render "$TMP/job.json" --workers 2 --out "$TMP/once" \
    --progress none >"$TMP/once.log" 2>&1 || { cat "$TMP/once.log"; fail "render with a hang"; }
grep -q "task 2 ran longer than its task_timeout of 2 s on pool child [01] (pid [0-9]*): stopped" \
    "$TMP/once.log" || { cat "$TMP/once.log"; fail "the timeout is not reported"; }
grep -q "16 tasks, 1 retried (0 worker crashes, 1 stopped at their time limit)" "$TMP/once.log" || { cat "$TMP/once.log"; fail "no retry counted"; }
cmp "$TMP/ref/img.exr" "$TMP/once/img.exr" || fail "image differs after the timeout"

# 1b. The limit counts from a run's start in its pool child, never from
# the wait for a free child: one child, every task sleeping 0.5 s first
# (GI_FAULT_SLOW_TASK), so the last waits ~8 s, four times the limit;
# only the hung run of task 2 is stopped.
GI_FAULT_SLOW_TASK=$(seq -s, 0 15) GI_FAULT_SLOW_S=0.5 GI_FAULT_HANG_TASK=2:0 timeout 120 \
    "$GI" render "$TMP/job.json" --workers 1 --out "$TMP/queued" --progress none \
    >"$TMP/queued.log" 2>&1 || { cat "$TMP/queued.log"; fail "render with one child and a hang"; }
grep -q "16 tasks, 1 retried (0 worker crashes, 1 stopped at their time limit)" "$TMP/queued.log" ||
    { cat "$TMP/queued.log"; fail "waiting tasks were stopped, or the hang was not"; }
cmp "$TMP/ref/img.exr" "$TMP/queued/img.exr" || fail "image differs (one child)"

# 2. --task-timeout for a job with no limit of its own; task 2 hangs every
# time: after 4 runs (gi render's attempts) the render fails, saying why.
set +e
GI_FAULT_HANG_TASK=2:0,2:1,2:2,2:3 timeout 120 "$GI" render "$TMP/plain.json" --workers 2 \
    --out "$TMP/always" --progress none --task-timeout 1 >"$TMP/always.log" 2>&1
rc=$?
set -e
[ $rc -eq 1 ] || { cat "$TMP/always.log"; fail "a task that always hangs: exit $rc"; }
grep -q "task 2 failed 4 times; last error: task 2 ran longer than its task_timeout of 1 s on pool child" \
    "$TMP/always.log" || { cat "$TMP/always.log"; fail "no clear error naming the timeout"; }
[ ! -e "$TMP/always/img.exr" ] || fail "a failed render left an output"

# 3. The job's limit wins over --task-timeout: with 1000 s given, the hang
# is still stopped after the job's 2 s.
GI_FAULT_HANG_TASK=2:0 timeout 120 "$GI" render "$TMP/job.json" --workers 2 --out "$TMP/wins" \
    --progress none --task-timeout 1000 >"$TMP/wins.log" 2>&1 ||
    { cat "$TMP/wins.log"; fail "render with a hang and --task-timeout 1000"; }
grep -q "task_timeout of 2 s" "$TMP/wins.log" || { cat "$TMP/wins.log"; fail "the job's limit lost"; }

# 4. Bad limits.
for v in 0.5 -1 abc 2000000; do
    "$GI" render "$TMP/plain.json" --out "$TMP/bad" --task-timeout "$v" >"$TMP/bad.log" 2>&1 &&
        fail "--task-timeout $v accepted"
    grep -q -- "--task-timeout must be 0 (no limit) or seconds in \[1, 1e+06\], got \"$v\"" \
        "$TMP/bad.log" || { cat "$TMP/bad.log"; fail "no clear error for --task-timeout $v"; }
done
"$GI" --help | grep -q -- "--task-timeout S" || fail "gi --help does not name --task-timeout"
sed 's/"task_timeout": 2/"task_timeout": 0/' "$TMP/job.json" >"$TMP/zero.json"
set +e
"$GI" render "$TMP/zero.json" --out "$TMP/zero" --progress none >"$TMP/zero.log" 2>&1
rc=$?
set -e
[ $rc -eq 2 ] || { cat "$TMP/zero.log"; fail "task_timeout 0: exit $rc"; }
grep -q "zero.json: task_timeout: " "$TMP/zero.log" || { cat "$TMP/zero.log"; fail "no clear error"; }
[ ! -e "$TMP/zero/img.exr" ] || fail "a refused job left an output"
echo ok
