# gi relight: new emissions from a finished radiosity job's factorization.
# The scene's own emission reproduces the job's outputs bit for bit (PLY
# without the scene; EXR with --images); other sets change them; bad
# emission files and damaged factorizations are one-line errors (exit 2).
. "$(dirname "$0")/lib.sh"
write_job "$TMP/job.json" <<JOB
{
  "name": "cb",
  "scene": "$SRC/scenes/cornell-box/scene.json",
  "method": "radiosity",
  "image": {"width": 40, "height": 32},
  "radiosity": {"patches": 80, "levels": 2, "rays": 256},
  "outputs": {"exr": "cb.exr", "ply": "cb.ply", "glb": "cb.glb", "report": "cb.json",
              "factorization": "cb.fact"}
}
JOB
"$GI_RELEASE" render "$TMP/job.json" --workers 2 --out "$TMP/out" --progress none >/dev/null ||
    fail "render"
cat >"$TMP/em.json" <<EM
{"emissions": [
  {"name": "scene"},
  {"name": "blue", "materials": {"light": [2, 4, 17]}},
  {"name": "block", "base": "none", "objects": {"tall_block": [1, 1, 1]}, "scale": 3}
]}
EM
"$GI" relight "$TMP/job.json" "$TMP/em.json" --out "$TMP/out" >"$TMP/relight.log" 2>&1 ||
    { cat "$TMP/relight.log"; fail "relight"; }
cat "$TMP/relight.log"
grep -q "relit 3 emission sets" "$TMP/relight.log" || fail "no summary"
cmp "$TMP/out/cb.ply" "$TMP/out/cb-scene.ply" || fail "the scene's emission does not reproduce the job's PLY"
cmp "$TMP/out/cb.glb" "$TMP/out/cb-scene.glb" || fail "the scene's emission does not reproduce the job's glTF"
if cmp -s "$TMP/out/cb.glb" "$TMP/out/cb-blue.glb"; then fail "a blue light changes no glTF"; fi
if cmp -s "$TMP/out/cb.ply" "$TMP/out/cb-blue.ply"; then fail "a blue light changes nothing"; fi
[ -s "$TMP/out/cb-block.ply" ] && [ -s "$TMP/out/cb-relight.json" ] || fail "outputs missing"
grep -q '"name":	"block"' "$TMP/out/cb-relight.json" || fail "report lacks the sets"
[ ! -e "$TMP/out/cb-scene.exr" ] || fail "an image without --images"
"$GI" relight "$TMP/job.json" "$TMP/em.json" --out "$TMP/out" --images --workers 2 >"$TMP/img.log" 2>&1 ||
    { cat "$TMP/img.log"; fail "relight --images"; }
cmp "$TMP/out/cb.exr" "$TMP/out/cb-scene.exr" || fail "the scene's emission does not reproduce the job's EXR"
cmp "$TMP/out/cb.ply" "$TMP/out/cb-scene.ply" || fail "PLY differs with --images"

# The emissions file the README and make demo use stays valid for the box.
"$GI" relight "$TMP/job.json" "$SRC/scenes/cornell-box/emissions.json" --out "$TMP/out" \
    >"$TMP/shipped.log" 2>&1 || { cat "$TMP/shipped.log"; fail "relight with scenes/cornell-box/emissions.json"; }
grep -q "relit 3 emission sets" "$TMP/shipped.log" || fail "the shipped emissions file"

# Errors: exit 2, one line, naming the file.
expect_error() {
    what=$1
    shift
    set +e
    "$GI" relight "$@" >"$TMP/stdout" 2>"$TMP/stderr"
    rc=$?
    set -e
    [ $rc -eq 2 ] || { cat "$TMP/stderr"; fail "relight $*: exit $rc, expected 2"; }
    [ "$(wc -l <"$TMP/stderr")" -eq 1 ] || fail "relight $*: not one line: $(cat "$TMP/stderr")"
    grep -qF -- "$what" "$TMP/stderr" || fail "relight $*: '$(cat "$TMP/stderr")' does not say '$what'"
}
echo '{"emissions": [{"name": "x", "materials": {"velvet": [1, 1, 1]}}]}' >"$TMP/bad1.json"
expect_error 'no material "velvet" in the scene (its materials: white, red, green, light)' \
    "$TMP/job.json" "$TMP/bad1.json" --out "$TMP/out"
echo '{"emissions": [{"name": "x", "objects": {"box": [1, 1, 1]}}]}' >"$TMP/bad3.json"
expect_error 'no object "box" in the scene (its objects: floor, light, ceiling,' \
    "$TMP/job.json" "$TMP/bad3.json" --out "$TMP/out"
# A factorization that is not there (another --out, or no render yet) says
# what to do.
expect_error "$TMP/elsewhere/cb.fact: no such file: relight reads the factorization the job wrote" \
    "$TMP/job.json" "$TMP/em.json" --out "$TMP/elsewhere"
[ ! -e "$TMP/elsewhere" ] || fail "a relight with no factorization made its --out"
# A two-sided material may reflect in a radiosity job, but an emission set
# may not light it: its elements would emit from their front face only. The
# factorization remembers which materials are two-sided (the scene is not
# read by a relight).
sed 's/"green": {"diffuse": \[0.14, 0.45, 0.091\]/&, "two_sided": true/' \
    "$SRC/scenes/cornell-box/scene.json" >"$TMP/two-sided.json"
grep -q '"two_sided": true}' "$TMP/two-sided.json" || fail "no two-sided green in the scene copy"
write_job "$TMP/two-sided-job.json" <<JOB
{"name": "ts", "scene": "$TMP/two-sided.json", "method": "radiosity",
 "image": {"width": 40, "height": 32}, "radiosity": {"patches": 80, "levels": 2, "rays": 256},
 "outputs": {"ply": "ts.ply", "factorization": "ts.fact"}}
JOB
"$GI_RELEASE" render "$TMP/two-sided-job.json" --workers 2 --out "$TMP/ts" --progress none \
    >/dev/null || fail "render with a two-sided reflector"
echo '{"emissions": [{"name": "glow", "materials": {"green": [1, 1, 1]}}]}' >"$TMP/ts-em.json"
expect_error 'emissions[0] ("glow"): material "green" is two-sided' \
    "$TMP/two-sided-job.json" "$TMP/ts-em.json" --out "$TMP/ts"
[ ! -e "$TMP/ts/ts-glow.ply" ] || fail "a refused relight wrote its PLY"
echo '{"emissions": [{"name": "glow", "materials": {"white": [1, 1, 1]}}]}' >"$TMP/ts-em.json"
"$GI" relight "$TMP/two-sided-job.json" "$TMP/ts-em.json" --out "$TMP/ts" >/dev/null 2>&1 ||
    fail "relight of a one-sided material beside a two-sided one"
echo '{"emissions": [{"name": "x", "scale": "big"}]}' >"$TMP/bad2.json"
expect_error "bad2.json: emissions[0].scale" "$TMP/job.json" "$TMP/bad2.json" --out "$TMP/out"
cp "$TMP/out/cb.fact" "$TMP/good.fact"
head -c 1000 "$TMP/good.fact" >"$TMP/out/cb.fact"
expect_error "cb.fact: not a valid factorization file" "$TMP/job.json" "$TMP/em.json" --out "$TMP/out"
printf 'X' | dd of="$TMP/out/cb.fact" bs=1 seek=5000 conv=notrunc 2>/dev/null
cp "$TMP/good.fact" "$TMP/out/cb.fact"
printf 'X' | dd of="$TMP/out/cb.fact" bs=1 seek=5000 conv=notrunc 2>/dev/null
expect_error "checksum" "$TMP/job.json" "$TMP/em.json" --out "$TMP/out"
expect_error "usage" "$TMP/job.json"
expect_error "--threads" "$TMP/job.json" "$TMP/em.json" --threads 0
write_job "$TMP/pt.json" <<JOB
{
  "name": "cb",
  "scene": "$SRC/scenes/cornell-box/scene.json",
  "method": "pt",
  "image": {"width": 40, "height": 32},
  "outputs": {"exr": "cb.exr"}
}
JOB
expect_error "needs a radiosity job" "$TMP/pt.json" "$TMP/em.json" --out "$TMP/out"

# Outputs that would replace what the relight reads are refused before
# anything is written (exit 2, naming the file), as gi render refuses them.
refused() { # WHAT FILE... : each FILE is unchanged and the refusal says WHAT
    what=$1
    shift
    grep -qF -- "would replace one of the job's own files ($what)" "$TMP/stderr" ||
        fail "'$(cat "$TMP/stderr")' does not say it would replace $what"
    for f in "$@"; do cmp "$f" "$f.orig" || fail "$f was replaced"; done
    [ -z "$(find "$TMP/o2" -newer "$TMP/o2/stamp" ! -name stamp)" ] || fail "something was written"
}
clash_job() { # clash_job FILE SCENE OUTPUTS: the job above, with its scene and outputs
    write_job "$1" <<JOB
{"name": "cb", "scene": "$2", "method": "radiosity", "image": {"width": 40, "height": 32},
 "radiosity": {"patches": 80, "levels": 2, "rays": 256}, "outputs": {$3}}
JOB
}
mkdir "$TMP/o2"
cp "$TMP/good.fact" "$TMP/o2/cb-scene.fact"
cp "$TMP/good.fact" "$TMP/o2/cb-scene.fact.orig"
clash_job "$TMP/clash.json" "$SRC/scenes/cornell-box/scene.json" \
    '"ply": "cb.fact", "factorization": "cb-scene.fact"'
touch "$TMP/o2/stamp"
expect_error "outputs.ply: $TMP/o2/cb-scene.fact" "$TMP/clash.json" "$TMP/em.json" --out "$TMP/o2"
refused "the factorization it relights" "$TMP/o2/cb-scene.fact"
# The emissions file, by another path to the same file.
cp "$TMP/em.json" "$TMP/o2/cb-relight.json"
cp "$TMP/em.json" "$TMP/o2/cb-relight.json.orig"
clash_job "$TMP/clash.json" "$SRC/scenes/cornell-box/scene.json" \
    '"report": "cb.json", "factorization": "cb-scene.fact"'
touch "$TMP/o2/stamp"
expect_error "outputs.report" "$TMP/clash.json" "$TMP/o2/../o2/cb-relight.json" --out "$TMP/o2"
refused "the emissions file" "$TMP/o2/cb-relight.json"
# The job file itself, and its scene's files (read for this check only,
# without --images), and with --images an image over the scene.
cp "$SRC/scenes/cornell-box/scene.json" "$TMP/o2/cb-blue.json"
cp "$TMP/o2/cb-blue.json" "$TMP/o2/cb-blue.json.orig"
clash_job "$TMP/o2/cb-scene.json" cb-blue.json '"ply": "cb.json", "factorization": "cb-scene.fact"'
cp "$TMP/o2/cb-scene.json" "$TMP/o2/cb-scene.json.orig"
touch "$TMP/o2/stamp"
expect_error "outputs.ply: $TMP/o2/cb-scene.json" "$TMP/o2/cb-scene.json" "$TMP/em.json" \
    --out "$TMP/o2"
refused "the job file" "$TMP/o2/cb-scene.json"
echo '{"emissions": [{"name": "blue", "materials": {"light": [2, 4, 17]}}]}' >"$TMP/blue.json"
touch "$TMP/o2/stamp"
expect_error "outputs.ply: $TMP/o2/cb-blue.json" "$TMP/o2/cb-scene.json" "$TMP/blue.json" \
    --out "$TMP/o2"
refused "the scene's cb-blue.json" "$TMP/o2/cb-blue.json"
sed 's/"ply": "cb.json"/"exr": "cb.json"/' "$TMP/o2/cb-scene.json.orig" >"$TMP/o2/images.json"
touch "$TMP/o2/stamp"
expect_error "outputs.exr: $TMP/o2/cb-blue.json" "$TMP/o2/images.json" "$TMP/blue.json" \
    --out "$TMP/o2" --images --workers 1
refused "the scene's cb-blue.json" "$TMP/o2/cb-blue.json"
echo ok
