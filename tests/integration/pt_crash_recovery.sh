# A pool child killed in the middle of a task (fault hook, and a real
# SIGKILL from outside) fails only that task, which is retried elsewhere:
# the image is byte-identical to an undisturbed run.
. "$(dirname "$0")/lib.sh"
write_job "$TMP/job.json" <<JOB
{
  "scene": "$SRC/scenes/cornell-box/scene.json",
  "method": "pt",
  "image": {"width": 64, "height": 64},
  "pt": {"spp": 16, "tile": 16, "pass_spp": 4},
  "outputs": {"exr": "img.exr"}
}
JOB
"$GI" render "$TMP/job.json" --workers 2 --out "$TMP/ref" --progress none >/dev/null 2>&1 || fail "reference render"

# Task 3 dies on its first attempt, task 10 on its first two.
GI_FAULT_CRASH_TASK="3,10:0,10:1" "$GI" render "$TMP/job.json" --workers 2 --out "$TMP/hook" \
    --progress none >"$TMP/hook.log" 2>&1 || { cat "$TMP/hook.log"; fail "render with crashes"; }
grep -q "3 retried (3 worker crashes)" "$TMP/hook.log" || { cat "$TMP/hook.log"; fail "crashes not reported"; }
cmp "$TMP/ref/img.exr" "$TMP/hook/img.exr" || fail "image differs after injected crashes"

# A task that kills every child it runs on fails the job, with a clear error.
if GI_FAULT_CRASH_TASK="5:0,5:1,5:2,5:3" "$GI" render "$TMP/job.json" --workers 2 --out "$TMP/dead" \
    --progress none >"$TMP/dead.log" 2>&1; then
    fail "a task that always crashes did not fail the job"
fi
grep -q "task 5 failed 4 times" "$TMP/dead.log" || { cat "$TMP/dead.log"; fail "no clear error"; }
[ ! -e "$TMP/dead/img.exr" ] || fail "a failed job left an output"

# SIGKILL of a real child from outside, mid-render (slower job: release build).
sed 's/"spp": 16/"spp": 1024/' "$TMP/job.json" >"$TMP/long.json"
"$GI_RELEASE" render "$TMP/long.json" --workers 2 --out "$TMP/long-ref" --progress none >/dev/null 2>&1 ||
    fail "long reference"
render_killing_a_child "$TMP/long.json" "$TMP/long-kill" 0.3
cmp "$TMP/long-ref/img.exr" "$TMP/long-kill/img.exr" || fail "image differs after kill -9"
echo ok
