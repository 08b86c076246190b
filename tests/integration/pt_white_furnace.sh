# White furnace: inside a closed box whose walls all reflect 0.5 and emit
# 1.0, radiance is 1 / (1 - 0.5) = 2.0 everywhere (within 1%). With an
# albedo of 0.99 it is 100: Russian roulette must not starve long paths.
. "$(dirname "$0")/lib.sh"
cat >"$TMP/furnace.json" <<SCENE
{
  "camera": {"position": [0.1, -0.2, 0.15], "look_at": [1, 0.3, -0.4], "fov_y": 100},
  "materials": {"wall": {"diffuse": [0.5, 0.5, 0.5], "emission": [1, 1, 1]}},
  "objects": [{"name": "box", "material": "wall", "box": {"size": [2, 2, 2], "inward": true}}]
}
SCENE
write_job "$TMP/job.json" <<JOB
{
  "scene": "furnace.json",
  "method": "pt",
  "image": {"width": 12, "height": 8},
  "pt": {"spp": 32768, "tile": 4, "pass_spp": 4096},
  "outputs": {"exr": "furnace.exr"}
}
JOB
"$GI" render "$TMP/job.json" --workers 2 --out "$TMP/out" --progress none || fail "render"
"$IMGTOOL" check-const "$TMP/out/furnace.exr" 2.0 0.01 || fail "not 2.0 everywhere"
# Each strategy alone must agree as well. Next-event estimation alone has
# infinite variance where two walls meet (the 1/r^2 of nearby light points),
# so for it the image mean is checked, not every pixel.
for strategy in bsdf light; do
    sed "s/\"pass_spp\": 4096/\"pass_spp\": 4096, \"strategy\": \"$strategy\"/" "$TMP/job.json" >"$TMP/$strategy.json"
    "$GI_RELEASE" render "$TMP/$strategy.json" --workers 2 --out "$TMP/$strategy" --progress none >/dev/null ||
        fail "render ($strategy)"
    if [ $strategy = bsdf ]; then
        "$IMGTOOL" check-const "$TMP/$strategy/furnace.exr" 2.0 0.01 || fail "$strategy: not 2.0 everywhere"
    else
        "$IMGTOOL" check-mean "$TMP/$strategy/furnace.exr" 2.0 0.01 || fail "$strategy: mean is not 2.0"
    fi
done
# Albedo 0.99 (green; paths of ~100 bounces): a roulette capped at 0.95
# gave 92-96 (weights growing as (0.99 / 0.95)^bounces, infinite variance).
sed 's/"diffuse": \[0.5, 0.5, 0.5\]/"diffuse": [0.5, 0.99, 0.5]/' "$TMP/furnace.json" >"$TMP/bright.json"
sed 's/"scene": "furnace.json"/"scene": "bright.json"/; s/"spp": 32768/"spp": 1024/; s/"pass_spp": 4096/"pass_spp": 256/' \
    "$TMP/job.json" >"$TMP/bright-job.json"
"$GI_RELEASE" render "$TMP/bright-job.json" --workers 2 --out "$TMP/bright" --progress none >/dev/null ||
    fail "render (albedo 0.99)"
"$IMGTOOL" stats "$TMP/bright/furnace.exr" | awk '$1 == "mean" { g = $3 } END {
    if (g < 98.5 || g > 101.5) { print "albedo 0.99: mean green " g ", expected 100"; exit 1 } }' ||
    fail "albedo 0.99 furnace"
echo ok
