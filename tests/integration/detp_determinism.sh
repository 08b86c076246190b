# detp: the same job with 1, 2 and 3 pool workers gives byte-identical
# outputs (image, PLY, glTF, binary vertex file); pool children killed in the
# middle of photon batches and image tiles (fault hook, and a real SIGKILL
# from outside) change nothing.
. "$(dirname "$0")/lib.sh"
write_job "$TMP/job.json" <<JOB
{
  "scene": "$SRC/scenes/cornell-box/scene.json",
  "method": "detp",
  "seed": 7,
  "image": {"width": 48, "height": 40},
  "detp": {"photons": 60000, "batch": 5000, "subdivide": 40, "tile": 16, "image_spp": 2},
  "outputs": {"exr": "img.exr", "ply": "v.ply", "glb": "v.glb", "bin": "v.bin",
              "json": "report.json"}
}
JOB
for w in 1 2 3; do
    "$GI" render "$TMP/job.json" --workers $w --out "$TMP/w$w" --progress none >"$TMP/w$w.log" 2>&1 ||
        { cat "$TMP/w$w.log"; fail "render with $w workers"; }
done
for f in img.exr v.ply v.glb v.bin; do
    cmp "$TMP/w1/$f" "$TMP/w2/$f" || fail "$f: 1 vs 2 workers differ"
    cmp "$TMP/w1/$f" "$TMP/w3/$f" || fail "$f: 1 vs 3 workers differ"
done
grep -q '"batches":	12' "$TMP/w1/report.json" || fail "report: not 12 batches"
# A different seed gives other photons (the comparison above can fail).
sed 's/"seed": 7/"seed": 8/' "$TMP/job.json" >"$TMP/job8.json"
"$GI" render "$TMP/job8.json" --workers 2 --out "$TMP/s8" --progress none >/dev/null 2>&1 || fail "seed 8"
if cmp -s "$TMP/w1/v.bin" "$TMP/s8/v.bin"; then fail "seed does not change the result"; fi

# Batches 2 and 9 die on their first attempt, tile task 14 (the bake has
# 12 tasks: 0-11) on its first two.
GI_FAULT_CRASH_TASK="2,9:0,14:0,14:1" "$GI" render "$TMP/job.json" --workers 2 --out "$TMP/hook" \
    --progress none >"$TMP/hook.log" 2>&1 || { cat "$TMP/hook.log"; fail "render with crashes"; }
grep -q "4 retried (4 worker crashes)" "$TMP/hook.log" || { cat "$TMP/hook.log"; fail "crashes not reported"; }
for f in img.exr v.ply v.glb v.bin; do
    cmp "$TMP/w1/$f" "$TMP/hook/$f" || fail "$f differs after injected crashes"
done

# SIGKILL of a real child from outside, mid-bake (a longer job: release build).
sed -e 's/"photons": 60000/"photons": 3000000/' -e 's/"batch": 5000/"batch": 100000/' \
    "$TMP/job.json" >"$TMP/long.json"
"$GI_RELEASE" render "$TMP/long.json" --workers 2 --out "$TMP/long-ref" --progress none >/dev/null 2>&1 ||
    fail "long reference"
render_killing_a_child "$TMP/long.json" "$TMP/long-kill" 0.4
for f in img.exr v.ply v.glb v.bin; do
    cmp "$TMP/long-ref/$f" "$TMP/long-kill/$f" || fail "$f differs after kill -9"
done
echo ok
