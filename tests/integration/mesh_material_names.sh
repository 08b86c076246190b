# A mesh file's material name longer than gi takes (1000 bytes; assimp keeps
# 1023 and drops an OBJ's longer name with its colours, or cuts a glTF's,
# silently) is bad input: `gi render` says which file, which material and
# how long its name is, in one line, exits 2 and writes nothing. A name of
# 1000 bytes renders. The files are made here: OBJ + MTL, glTF.
. "$(dirname "$0")/lib.sh"
name_of() { head -c "$1" /dev/zero | tr '\0' 'm'; }
# The glTF's buffer: 3 float positions, 3 uint16 indices, 2 bytes of padding.
BUFFER=AACAvwAAAAAAAIC/AAAAAAAAAAAAAIA/AACAPwAAAAAAAIC/AAABAAIAAAA=

# The lamp: one triangle facing down, of material $2.
obj() {
    printf 'mtllib %s.mtl\nv -1 1 -1\nv 0 1 1\nv 1 1 -1\nusemtl %s\nf 1 3 2\n' "$1" "$2" \
        >"$TMP/$1.obj"
    printf 'newmtl %s\nKd 0 0 0\nKe 5 5 5\n' "$2" >"$TMP/$1.mtl"
}
gltf() {
    cat >"$TMP/$1.gltf" <<GLTF
{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
 "nodes": [{"mesh": 0, "translation": [0, 1, 0]}],
 "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
 "materials": [{"name": "$2", "emissiveFactor": [1, 1, 1]}],
 "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,$BUFFER"}],
 "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                 {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                "min": [-1, 0, -1], "max": [1, 0, 1]},
               {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]}
GLTF
}
job() { # job.json rendering a room lit by mesh file $1
    cat >"$TMP/scene-$1.json" <<SCENE
{"camera": {"position": [0, 0, -3], "look_at": [0, 0, 0], "fov_y": 60},
 "materials": {"wall": {"diffuse": [0.5, 0.5, 0.5]}},
 "objects": [{"name": "room", "material": "wall", "box": {"size": [4, 4, 4], "inward": true}},
             {"name": "lamp", "mesh": "$1"}]}
SCENE
    write_job "$TMP/job-$1.json" <<JOB
{"scene": "scene-$1.json", "method": "pt", "image": {"width": 8, "height": 8},
 "pt": {"spp": 1}, "outputs": {"exr": "o.exr"}}
JOB
}

obj long "$(name_of 1100)"
gltf long "$(name_of 5000)"
obj ok "$(name_of 1000)"
gltf ok "$(name_of 1000)"
for f in long.obj long.gltf; do
    job "$f"
    set +e
    "$GI" render "$TMP/job-$f.json" --out "$TMP/out-$f" --progress none >"$TMP/stdout" \
        2>"$TMP/stderr"
    rc=$?
    set -e
    msg=$(cat "$TMP/stderr")
    [ $rc -eq 2 ] || fail "$f: exit status $rc, expected 2 ($msg)"
    [ "$(wc -l <"$TMP/stderr")" -eq 1 ] || fail "$f: error is not one line: $msg"
    case $f in
    *.obj) want="$f: line 5: usemtl: the material's name (\"mmmm" ;;
    *) want="$f: material 0: its name (\"mmmm" ;;
    esac
    echo "$msg" | grep -qF -- "$want" || fail "$f: \"$msg\" does not say \"$want\""
    case $f in
    *.obj) want="is 1100 bytes long, over the limit of 1000" ;;
    *) want="is at least 1023 bytes long, over the limit of 1000" ;;
    esac
    echo "$msg" | grep -qF -- "$want" || fail "$f: \"$msg\" does not say \"$want\""
    [ ! -e "$TMP/out-$f" ] || [ -z "$(ls -A "$TMP/out-$f")" ] || fail "$f: output written"
    echo "ok  $msg"
done
for f in ok.obj ok.gltf; do
    job "$f"
    "$GI" render "$TMP/job-$f.json" --out "$TMP/out-$f" --workers 1 --progress none \
        >"$TMP/log" 2>&1 || { cat "$TMP/log"; fail "$f: a 1000-byte name does not render"; }
    [ -s "$TMP/out-$f/o.exr" ] || fail "$f: no image"
    echo "ok  $f renders"
done
