# radiosity camera paths (`radiosity.animation.camera`): the solution,
# view-independent, is computed once (one set of form-factor tasks) and
# each frame is its image from the frame's camera. Frame 2, at its key, is
# the still seen from that key's camera bit for bit; the factorization,
# the vertex outputs and the report are written once (no frame number),
# the vertex outputs the still's; the held frame 3 is frame 2 again with
# no tasks; 1 and 3 workers give the same bytes; `gi relight --images`
# renders every frame of every emission set (the scene's own set's frames
# are the job's); a render stopped between frames resumes to the same
# frames. A moving object, a block without a path and a path without an
# image output are refused naming the field.
. "$(dirname "$0")/lib.sh"
RAD='"patches": 40, "levels": 1, "rays": 256, "image_spp": 2, "tile": 16'
write_job "$TMP/cam.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "radiosity", "seed": 3,
 "image": {"width": 32, "height": 32},
 "radiosity": {$RAD,
   "animation": {"frames": 4, "camera": [{"frame": 0, $CAM_KEY0}, {"frame": 2, $CAM_KEY2}]}},
 "outputs": {"exr": "img.exr", "ply": "v.ply", "report": "r.json", "factorization": "f.gifac"}}
JOB
write_job "$TMP/still.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "radiosity", "seed": 3,
 "image": {"width": 32, "height": 32}, "camera": {$CAM_KEY2},
 "radiosity": {$RAD}, "outputs": {"exr": "still.exr", "ply": "v.ply"}}
JOB
FRAMES="0000 0001 0002 0003"

"$GI" validate "$SRC/scenes/cornell-box/radiosity-flythrough.json" >"$TMP/validate.out" 2>&1 ||
    { cat "$TMP/validate.out"; fail "validate the example"; }
"$GI" validate "$TMP/cam.json" >"$TMP/validate.out" 2>&1 || { cat "$TMP/validate.out"; fail "validate"; }
grep -q "^$TMP/cam.json: ok (radiosity, 4 frames, scene " "$TMP/validate.out" ||
    { cat "$TMP/validate.out"; fail "gi validate did not say the frames"; }
render "$TMP/cam.json" "$TMP/w1" 1
render "$TMP/cam.json" "$TMP/w3" 3
render "$TMP/still.json" "$TMP/still" 1
for f in $FRAMES; do
    [ -s "$TMP/w1/img.$f.exr" ] || fail "no img.$f.exr"
    cmp "$TMP/w1/img.$f.exr" "$TMP/w3/img.$f.exr" || fail "1 vs 3 workers: img.$f.exr differs"
    for k in v.$f.ply r.$f.json f.$f.gifac; do
        [ ! -e "$TMP/w1/$k" ] || fail "$k was written: the solution's outputs are the same each frame"
    done
done
[ -s "$TMP/w1/r.json" ] || fail "no report"
for k in v.ply f.gifac; do # (the report has timings)
    cmp "$TMP/w1/$k" "$TMP/w3/$k" || fail "1 vs 3 workers: $k differs"
done
cmp "$TMP/still/v.ply" "$TMP/w1/v.ply" || fail "the vertex outputs are not the still's"
camera_path_frames "$TMP/w1" img "$TMP/still/still.exr"
# 1 form-factor task, 4 tiles for each of frames 0, 1 and 2.
grep -q "^  13 tasks$" "$TMP/w1.log" || { cat "$TMP/w1.log"; fail "not one solution and 4 tiles a moving frame"; }

# Relit with images: every frame of every set.
"$GI" relight "$TMP/cam.json" "$SRC/scenes/cornell-box/emissions.json" --out "$TMP/w1" --images \
    >"$TMP/relight.log" 2>&1 || { cat "$TMP/relight.log"; fail "gi relight --images"; }
for f in $FRAMES; do
    for set in scene blue lamp; do
        [ -s "$TMP/w1/img-$set.$f.exr" ] || { cat "$TMP/relight.log"; fail "relight: no img-$set.$f.exr"; }
    done
    cmp "$TMP/w1/img-scene.$f.exr" "$TMP/w1/img.$f.exr" || fail "relight: the scene's set, frame $f"
done

# Refusals, each naming the field.
refused() { # refused NAME SED-EXPRESSION MESSAGE
    sed "$2" "$TMP/cam.json" >"$TMP/$1.json"
    st=0
    "$GI" validate "$TMP/$1.json" >"$TMP/$1.out" 2>&1 || st=$?
    [ $st -ne 0 ] && grep -q -- "$3" "$TMP/$1.out" || { cat "$TMP/$1.out"; fail "$1: exit $st"; }
}
refused object 's/"frames": 4,/"frames": 4, "object": "tall_block",/' \
    'radiosity.animation.object: radiosity jobs take a camera path only'
refused keys 's/"frames": 4,/"frames": 4, "keyframes": [{"frame": 0}],/' \
    'radiosity.animation.keyframes: radiosity jobs take a camera path only'
refused nopath 's/"frames": 4, "camera": \[.*\]}},/"frames": 4}},/' \
    'radiosity.animation.camera: missing (required)'
refused noimage 's/"exr": "img.exr", //' \
    'radiosity.animation.camera: a camera path needs an image output'

# Stopped (SIGINT) once frame 1 is written, resumed: the same frames.
sed -e 's/"image_spp": 2/"image_spp": 256/' -e 's/"frames": 4,/"frames": 8,/' \
    -e 's/{"frame": 2, "position"/{"frame": 7, "position"/' "$TMP/cam.json" >"$TMP/long.json"
grep -q '"frame": 7' "$TMP/long.json" || fail "long job not made"
stop_and_resume_animation "$TMP/long.json" "$TMP/long" img 0000 0001 0002 0003 0004 0005 0006 0007
echo "radiosity camera path: frames = stills from their cameras, held, 1/3 workers, relit, resumed"
