# pt animation (pt.animation: one mobile object keyframed, as detp's) with
# `gi render`: every frame's image is byte-identical with 1 and 3 workers
# and after injected crashes; a frame is the still of its pose (a one-frame
# animation keyed there), bit for bit; a held frame is the frame before's
# bytes; pixels whose paths never meet the mobile are the same bits in
# every frame (the same random numbers each frame), the others are not.
# A render stopped between frames, and one whose frame image could not be
# written, resume to the same frames. A camera path's frame is the still
# from its camera. Bad animation blocks are refused naming the field.
. "$(dirname "$0")/lib.sh"
write_job "$TMP/job.json" <<JOB
{
  "scene": "$SRC/scenes/cornell-box/scene-mobile.json",
  "method": "pt",
  "seed": 4,
  "image": {"width": 32, "height": 32},
  "pt": {"spp": 8, "tile": 16, "pass_spp": 4,
         "animation": {"object": "mobile", "frames": 5,
                       "keyframes": [{"frame": 0, "translate": [340, -338.9, -90]},
                                     {"frame": 3, "translate": [200, -338.9, 35],
                                      "rotate": {"axis": [0, 1, 0], "degrees": 40}}]}},
  "outputs": {"exr": "img.exr", "png": "img.png"}
}
JOB
FRAMES="0000 0001 0002 0003 0004"
same_frames() { # same_frames DIR_A DIR_B WHAT
    for f in $FRAMES; do
        for k in img.$f.exr img.$f.png; do
            cmp "$1/$k" "$2/$k" || fail "$3: $k differs"
        done
    done
}

# Refusals, each naming the field.
refused() { # refused NAME SED-EXPRESSION MESSAGE
    sed "$2" "$TMP/job.json" >"$TMP/$1.json"
    st=0
    "$GI" validate "$TMP/$1.json" >"$TMP/$1.out" 2>&1 || st=$?
    [ $st -ne 0 ] && grep -q "$3" "$TMP/$1.out" || { cat "$TMP/$1.out"; fail "$1: exit $st"; }
}
refused static 's/"object": "mobile"/"object": "tall_block"/' \
    'pt.animation.object: object "tall_block" is not mobile'
refused missing 's/"object": "mobile"/"object": "ghost"/' 'pt.animation.object: no object "ghost"'
refused frames 's/"frames": 5,/"frames": 0,/' 'pt.animation.frames'
refused key 's/{"frame": 3,/{"frame": 5,/' \
    'pt.animation.keyframes\[1\].frame: 5 is not less than pt.animation.frames (5)'
refused detp_key 's/"frames": 5,/"frames": 5, "update": "full",/' \
    'pt.animation.update: unknown key (expected one of: object, frames, keyframes, camera)'
for j in "$SRC/scenes/cornell-box/pt-animation.json" "$TMP/job.json"; do
    "$GI" validate "$j" >"$TMP/validate.out" 2>&1 ||
        { cat "$TMP/validate.out"; fail "validate $j"; }
done
grep -q "^$TMP/job.json: ok (pt, 5 frames, scene " "$TMP/validate.out" ||
    { cat "$TMP/validate.out"; fail "gi validate did not say the animation's frames"; }

render "$TMP/job.json" "$TMP/w1" 1
render "$TMP/job.json" "$TMP/w3" 3 json
same_frames "$TMP/w1" "$TMP/w3" "1 vs 3 workers"
grep -q '"event":"progress".*"frame":4,"frames":5' "$TMP/w3.log" ||
    { cat "$TMP/w3.log"; fail "progress did not count the frames"; }
# 8 tasks a frame (4 tiles, 2 passes); frame 4 holds frame 3's pose.
GI_FAULT_CRASH_TASK="3:0,9:0,20:0,20:1" render "$TMP/job.json" "$TMP/crash" 2
grep -q "retried (4 worker crashes)" "$TMP/crash.log" ||
    { cat "$TMP/crash.log"; fail "crashes not reported"; }
same_frames "$TMP/w1" "$TMP/crash" "after injected crashes"

# Frame 3 is the still of its key's pose.
sed -e 's/"frames": 5,/"frames": 1,/' -e 's/{"frame": 0, "translate": \[340, -338.9, -90\]},//' \
    -e 's/{"frame": 3,/{"frame": 0,/' "$TMP/job.json" >"$TMP/pose3.json"
render "$TMP/pose3.json" "$TMP/pose3" 2
cmp "$TMP/pose3/img.0000.exr" "$TMP/w1/img.0003.exr" || fail "frame 3 is not the still of its pose"
cmp "$TMP/w1/img.0003.exr" "$TMP/w1/img.0004.exr" || fail "the held frame 4 differs from frame 3"
grep -q "^  32 tasks$" "$TMP/w1.log" ||
    { cat "$TMP/w1.log"; fail "not 8 tasks a frame, none for the held one"; }
# The frames differ where the mobile is met, and only there.
for f in 0001 0003; do
    same=$("$IMGTOOL" same-pixels "$TMP/w1/img.0000.exr" "$TMP/w1/img.$f.exr") ||
        fail "same-pixels"
    n=${same%% of*}
    [ "$n" -gt 64 ] && [ "$n" -lt 1024 ] || fail "frames 0000 and $f: $same"
done

# Stopped (SIGINT) once frame 1 is written, resumed: the same frames.
# (0.2 s a frame here, 2 cores: the stop comes frames before the end.)
sed 's/"spp": 8, "tile": 16, "pass_spp": 4,/"spp": 512, "tile": 16, "pass_spp": 64,/' \
    "$TMP/job.json" >"$TMP/long.json"
grep -q '"spp": 512' "$TMP/long.json" || fail "long job not made"
# shellcheck disable=SC2086
stop_and_resume_animation "$TMP/long.json" "$TMP/long" img $FRAMES

# Frame 2's image cannot be written (a directory in its way): the render
# fails naming it and keeps its work; once the way is clear, --resume
# writes frame 2 and renders the frames after it.
mkdir -p "$TMP/blocked/img.0002.exr"
st=0
"$GI_RELEASE" render "$TMP/job.json" --workers 2 --out "$TMP/blocked" --progress none \
    >"$TMP/blocked.log" 2>&1 || st=$?
[ $st -eq 1 ] && grep -q "img.0002.exr: rename: " "$TMP/blocked.log" ||
    { cat "$TMP/blocked.log"; fail "blocked frame: exit $st"; }
[ ! -e "$TMP/blocked/img.0003.exr" ] || fail "frames after the blocked one were written"
rmdir "$TMP/blocked/img.0002.exr"
"$GI_RELEASE" render "$TMP/job.json" --workers 2 --out "$TMP/blocked" --progress none --resume \
    >"$TMP/unblocked.log" 2>&1 || { cat "$TMP/unblocked.log"; fail "resume, unblocked"; }
for f in $FRAMES; do
    cmp "$TMP/w1/img.$f.exr" "$TMP/blocked/img.$f.exr" || fail "unblocked: img.$f.exr differs"
done
# A camera path, nothing moving (the plain Cornell box): frame 2, at its
# key, is the still seen from that key's camera (the job's "camera"), bit
# for bit; frame 3 holds it; frame 1, between the keys, is neither end.
write_job "$TMP/cam.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "pt", "seed": 4,
 "image": {"width": 32, "height": 32},
 "pt": {"spp": 4, "tile": 16,
        "animation": {"frames": 4, "camera": [
          {"frame": 0, "position": [278, 273, -800], "look_at": [278, 273, 0], "fov_y": 39.3},
          {"frame": 2, "position": [100, 300, -600], "look_at": [278, 200, 300],
           "up": [0, 1, 0], "fov_y": 50}]}},
 "outputs": {"exr": "img.exr"}}
JOB
write_job "$TMP/cam-still.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "pt", "seed": 4,
 "image": {"width": 32, "height": 32},
 "camera": {"position": [100, 300, -600], "look_at": [278, 200, 300], "up": [0, 1, 0],
            "fov_y": 50},
 "pt": {"spp": 4, "tile": 16}, "outputs": {"exr": "still.exr"}}
JOB
render "$TMP/cam.json" "$TMP/cam" 2
render "$TMP/cam-still.json" "$TMP/cam-still" 1
camera_path_frames "$TMP/cam" img "$TMP/cam-still/still.exr"
sed 's/"frames": 4, "camera"/"frames": 4, "keyframes": [{"frame": 0}], "camera"/' "$TMP/cam.json" \
    >"$TMP/cam-keys.json"
st=0
"$GI" validate "$TMP/cam-keys.json" >"$TMP/cam-keys.out" 2>&1 || st=$?
[ $st -ne 0 ] && grep -q "pt.animation.keyframes: keys for no object" "$TMP/cam-keys.out" ||
    { cat "$TMP/cam-keys.out"; fail "keys without an object: exit $st"; }
echo "pt animation frames identical: 1/3 workers, crashes, still of the pose, held, resumed; camera path"
