# A scene of many distinct mesh files (one importer process serves them in
# turn) gives the same image as the same cubes made from one mesh file, each
# import on its own; and a file the importer dies on among good ones fails the
# load naming that file, exit 2, nothing written, while its neighbours import.
. "$(dirname "$0")/lib.sh"
N=40
SCENEGEN="$BUILD/release/scenes/gi_scenegen"
"$SCENEGEN" grid "$TMP/one" --objects $N --mesh
"$SCENEGEN" grid "$TMP/files" --objects $N --mesh-files
[ "$(ls "$TMP/files"/cube*.obj | wc -l)" -gt $N ] || fail "gi_scenegen wrote too few OBJs"
for d in one files; do
    write_job "$TMP/$d/job.json" <<JOB
{"scene": "scene.json", "method": "pt", "seed": 3, "image": {"width": 24, "height": 24},
 "pt": {"spp": 2, "tile": 8}, "outputs": {"exr": "o.exr"}}
JOB
    "$GI" validate "$TMP/$d/scene.json" >"$TMP/$d.validate" 2>&1 ||
        { cat "$TMP/$d.validate"; fail "$d: gi validate"; }
    "$GI" render "$TMP/$d/job.json" --workers 2 --out "$TMP/out-$d" --progress none \
        >"$TMP/$d.log" 2>&1 || { cat "$TMP/$d.log"; fail "$d: gi render"; }
done
cmp "$TMP/out-one/o.exr" "$TMP/out-files/o.exr" ||
    fail "$N distinct mesh files render differently from one file instanced $N times"

# cube17 is now assimp_abort.ply (assimp aborts on it); the files before and
# after it are good, and the error names it and its object.
cp "$SRC/tests/data/meshes/assimp_abort.ply" "$TMP/files/bad17.ply"
sed 's/"cube17\.obj"/"bad17.ply"/' "$TMP/files/scene.json" >"$TMP/files/bad.json"
grep -q bad17.ply "$TMP/files/bad.json" || fail "the scene names no bad file"
sed 's/scene\.json/bad.json/' "$TMP/files/job.json" >"$TMP/files/badjob.json"
for cmd in validate render; do
    set +e
    case $cmd in
    validate) "$GI" validate "$TMP/files/bad.json" >"$TMP/stdout" 2>"$TMP/stderr" ;;
    render) "$GI" render "$TMP/files/badjob.json" --workers 1 --out "$TMP/out-bad" \
        --progress none >"$TMP/stdout" 2>"$TMP/stderr" ;;
    esac
    rc=$?
    set -e
    msg=$(cat "$TMP/stderr")
    [ $rc -eq 2 ] || fail "$cmd: exit status $rc, expected 2 ($msg)"
    case $msg in
    *"objects[19].mesh: bad17.ply: "*"the importer (assimp) died"*) ;;
    *) fail "$cmd: no objects[19].mesh, bad17.ply and the importer's death in: $msg" ;;
    esac
    case $msg in *cube[0-9]*.obj*) fail "$cmd: a good file is blamed: $msg" ;; esac
done
[ ! -e "$TMP/out-bad/o.exr" ] || fail "render of the bad scene wrote an image"
echo ok
