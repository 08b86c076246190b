# Radiosity: the same job with 1, 2 and 3 pool workers gives byte-identical
# outputs (factorization, PLY, EXR), and so does a job whose children are
# killed while computing form-factor rows and image tiles.
. "$(dirname "$0")/lib.sh"
write_job "$TMP/job.json" <<JOB
{
  "scene": "$SRC/scenes/cornell-box/scene.json",
  "method": "radiosity",
  "seed": 7,
  "image": {"width": 48, "height": 40},
  "radiosity": {"patches": 60, "levels": 2, "rays": 256, "task_elements": 50, "tile": 16},
  "outputs": {"exr": "r.exr", "ply": "r.ply", "factorization": "r.fact"}
}
JOB
for w in 1 2 3; do
    "$GI" render "$TMP/job.json" --workers $w --out "$TMP/w$w" --progress none >"$TMP/w$w.log" 2>&1 ||
        { cat "$TMP/w$w.log"; fail "render with $w workers"; }
done
for f in r.fact r.ply r.exr; do
    cmp "$TMP/w1/$f" "$TMP/w2/$f" || fail "$f: 1 vs 2 workers differ"
    cmp "$TMP/w1/$f" "$TMP/w3/$f" || fail "$f: 1 vs 3 workers differ"
done
tasks=$(sed -n 's/^  \([0-9]*\) tasks.*/\1/p' "$TMP/w1.log")
[ "$tasks" -gt 20 ] || fail "expected many tasks, got '$tasks'"
# Children killed: a form-factor block (task 3, twice) and an image tile
# (the last task).
last=$((tasks - 1))
GI_FAULT_CRASH_TASK="3:0,3:1,$last:0" "$GI" render "$TMP/job.json" --workers 2 --out "$TMP/crash" \
    --progress none >"$TMP/crash.log" 2>&1 || { cat "$TMP/crash.log"; fail "render with crashes"; }
grep -q "3 retried (3 worker crashes)" "$TMP/crash.log" || { cat "$TMP/crash.log"; fail "crashes not reported"; }
for f in r.fact r.ply r.exr; do
    cmp "$TMP/w1/$f" "$TMP/crash/$f" || fail "$f differs after crashes"
done
# A different seed casts different rays (so the checks above can fail).
sed 's/"seed": 7/"seed": 8/' "$TMP/job.json" >"$TMP/job8.json"
"$GI" render "$TMP/job8.json" --workers 2 --out "$TMP/s8" --progress none >/dev/null 2>&1 || fail "seed 8"
if cmp -s "$TMP/w1/r.fact" "$TMP/s8/r.fact"; then fail "the seed does not change the form factors"; fi
echo ok
