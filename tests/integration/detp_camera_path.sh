# detp camera paths (`detp.animation.camera`). Nothing moving: the light
# is baked once (a still bake: one set of batch tasks) and each frame is
# its image from the frame's camera; frame 2, at its key, is the still
# seen from that key's camera bit for bit, the vertex outputs are the
# still's, written once (no frame number), the held frame 3 is frame 2
# again with no tasks, 1 and 3 workers give the same bytes, and a render
# stopped between frames resumes to the same frames. A still bake's options the incremental
# update refuses (visible_area, photon_map) are allowed. With the mobile
# moving too, the camera changes the images only: frame 0 (the job's
# camera) and frame 2 (its key's) are those of the same animation seen
# from a fixed camera there, every frame's lighting is theirs. A camera
# path with no image output is refused naming the field.
. "$(dirname "$0")/lib.sh"
DETP='"photons": 48000, "batch": 12000, "subdivide": 60, "tile": 16, "image_spp": 1'
write_job "$TMP/cam.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "detp", "seed": 5,
 "image": {"width": 32, "height": 32},
 "detp": {$DETP,
          "animation": {"frames": 4, "camera": [{"frame": 0, $CAM_KEY0}, {"frame": 2, $CAM_KEY2}]}},
 "outputs": {"exr": "img.exr", "ply": "v.ply", "json": "report.json"}}
JOB
write_job "$TMP/still.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "detp", "seed": 5,
 "image": {"width": 32, "height": 32}, "camera": {$CAM_KEY2},
 "detp": {$DETP}, "outputs": {"exr": "still.exr", "ply": "v.ply"}}
JOB
FRAMES="0000 0001 0002 0003"

for j in "$SRC/scenes/cornell-box/detp-flythrough.json" "$TMP/cam.json"; do
    "$GI" validate "$j" >"$TMP/validate.out" 2>&1 || { cat "$TMP/validate.out"; fail "validate $j"; }
done
grep -q "^$TMP/cam.json: ok (detp, 4 frames, scene " "$TMP/validate.out" ||
    { cat "$TMP/validate.out"; fail "gi validate did not say the frames"; }
render "$TMP/cam.json" "$TMP/w1" 1
render "$TMP/cam.json" "$TMP/w3" 3
render "$TMP/still.json" "$TMP/still" 1
for f in $FRAMES; do
    for k in img.$f.exr report.$f.json; do
        [ -s "$TMP/w1/$k" ] || fail "no $k"
    done
    [ ! -e "$TMP/w1/v.$f.ply" ] || fail "the vertex outputs were written for frame $f"
    cmp "$TMP/w1/img.$f.exr" "$TMP/w3/img.$f.exr" || fail "1 vs 3 workers: img.$f.exr differs"
done
cmp "$TMP/still/v.ply" "$TMP/w1/v.ply" || fail "the vertex outputs are not the still's"
cmp "$TMP/w1/v.ply" "$TMP/w3/v.ply" || fail "1 vs 3 workers: v.ply differs"
camera_path_frames "$TMP/w1" img "$TMP/still/still.exr"
# 4 batches once, 4 tiles for each of frames 0, 1 and 2.
grep -q "^  16 tasks$" "$TMP/w1.log" || { cat "$TMP/w1.log"; fail "not one bake and 4 tiles a moving frame"; }
python3 - "$TMP/w1/report.0001.json" <<'PY' || fail "frame 1's report"
import json, sys
a = json.load(open(sys.argv[1]))["animation"]
assert a["frame"] == 1 and a["frames"] == 4, a
assert a["camera"]["position"] == [189, 286.5, -700] and abs(a["camera"]["fov_y"] - 44.65) < 1e-5, a
PY

# A still bake's options are a camera path's too.
sed 's/"image_spp": 1,/"image_spp": 1, "artifact_control": "visible_area", "estimator": "photon_map",/' \
    "$TMP/cam.json" >"$TMP/vis.json"
grep -q visible_area "$TMP/vis.json" || fail "vis job not made"
"$GI" validate "$TMP/vis.json" >"$TMP/vis.out" 2>&1 || { cat "$TMP/vis.out"; fail "visible_area with a camera path"; }
sed 's/"outputs": {"exr": "img.exr", "ply": "v.ply", "json": "report.json"}/"outputs": {"ply": "v.ply"}/' \
    "$TMP/cam.json" >"$TMP/noimg.json"
st=0
"$GI" validate "$TMP/noimg.json" >"$TMP/noimg.out" 2>&1 || st=$?
[ $st -ne 0 ] && grep -q "detp.animation.camera: a camera path needs an image output" "$TMP/noimg.out" ||
    { cat "$TMP/noimg.out"; fail "a camera path with no image: exit $st"; }

# The mobile moving and the camera along a path.
mobile() { # mobile OUT CAMERA [CAMERA-PATH]
    write_job "$1" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene-mobile.json", "method": "detp", "seed": 5,
 "image": {"width": 32, "height": 32}, "camera": {$2},
 "detp": {$DETP,
          "animation": {"object": "mobile", "frames": 3,
                        "keyframes": [{"frame": 0, "translate": [340, -338.9, -90]},
                                      {"frame": 2, "translate": [268, -338.9, -20.4]}]${3:-}}},
 "outputs": {"exr": "img.exr", "ply": "v.ply"}}
JOB
}
mobile "$TMP/mc.json" "$CAM_KEY0" ", \"camera\": [{\"frame\": 0, $CAM_KEY0}, {\"frame\": 2, $CAM_KEY2}]"
mobile "$TMP/m0.json" "$CAM_KEY0"
mobile "$TMP/m2.json" "$CAM_KEY2"
for j in mc m0 m2; do render "$TMP/$j.json" "$TMP/$j" 2; done
cmp "$TMP/mc/img.0000.exr" "$TMP/m0/img.0000.exr" || fail "moving: frame 0 is not its camera's"
cmp "$TMP/mc/img.0002.exr" "$TMP/m2/img.0002.exr" || fail "moving: frame 2 is not its key camera's"
for f in 0000 0001 0002; do
    cmp "$TMP/mc/v.$f.ply" "$TMP/m0/v.$f.ply" || fail "moving: the camera changed frame $f's light"
done

# Stopped (SIGINT) once frame 1 is written, resumed: the same frames.
sed -e 's/"image_spp": 1/"image_spp": 256/' -e 's/"frames": 4,/"frames": 8,/' \
    -e 's/{"frame": 2, "position"/{"frame": 7, "position"/' "$TMP/cam.json" >"$TMP/long.json"
grep -q '"frame": 7' "$TMP/long.json" || fail "long job not made"
stop_and_resume_animation "$TMP/long.json" "$TMP/long" img 0000 0001 0002 0003 0004 0005 0006 0007
echo "detp camera path: frames = stills from their cameras, held, 1/3 workers, resumed; with a mobile"
