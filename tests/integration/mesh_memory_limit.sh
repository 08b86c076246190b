# The mesh importer's child process has a memory limit: a small glTF whose
# nodes form a DAG (each names the next twice, 24 deep) makes assimp expand
# it into gigabytes of meshes. The import fails with a clear message instead
# of taking what the machine has. (Release build: AddressSanitizer's shadow
# memory rules an address-space limit out.)
. "$(dirname "$0")/lib.sh"
# Padded to 10 MB: 25 s of import time, so that memory, not time, runs out
# first on a loaded machine.
cp "$SRC/tests/data/meshes/dag24.gltf" "$TMP/dag.gltf"
head -c 10000000 /dev/zero | tr '\0' ' ' >>"$TMP/dag.gltf"
cat >"$TMP/scene.json" <<'SCENE'
{"camera": {"position": [0, 0, -3], "look_at": [0, 0, 0], "fov_y": 60},
 "materials": {"wall": {"diffuse": [0.5, 0.5, 0.5]},
               "lamp": {"diffuse": [0.5, 0.5, 0.5], "emission": [5, 5, 5]}},
 "objects": [{"name": "room", "material": "wall", "box": {"size": [4, 4, 4], "inward": true}},
             {"name": "m", "mesh": "dag.gltf"}]}
SCENE
write_job "$TMP/job.json" <<'JOB'
{"scene": "scene.json", "method": "pt", "image": {"width": 8, "height": 8}, "pt": {"spp": 1},
 "outputs": {"exr": "o.exr"}}
JOB
set +e
"$GI_RELEASE" validate "$TMP/job.json" >"$TMP/out.log" 2>&1
rc=$?
set -e
[ $rc -eq 2 ] || { cat "$TMP/out.log"; fail "exit $rc, want 2"; }
grep -q "dag.gltf: cannot import: the importer ran out of its memory limit" "$TMP/out.log" ||
    { cat "$TMP/out.log"; fail "no memory limit message"; }
[ "$(wc -l <"$TMP/out.log")" -eq 1 ] || { cat "$TMP/out.log"; fail "not one line"; }
echo ok
