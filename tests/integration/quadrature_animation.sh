# quadrature animation (quadrature.animation: one mobile object keyframed,
# as pt's and detp's): every frame's image and report (timings aside) are
# byte-identical with 1 and 3 workers and after injected crashes; a frame
# is the still of its pose (a one-frame animation keyed there), bit for
# bit; a held frame is the frame before's image; each frame's report names
# its frame and pose, and refines from round 0. A render whose frame image
# could not be written resumes from its checkpoint (the frame's whole
# result) to the same frames. A camera path's frame is the still from its
# camera.
. "$(dirname "$0")/lib.sh"
write_job "$TMP/job.json" <<JOB
{
  "scene": "$SRC/scenes/cornell-box/scene-mobile.json",
  "method": "quadrature",
  "image": {"width": 32, "height": 32},
  "quadrature": {"dims": 4, "max_evals": 400000, "round_tasks": 4,
                 "animation": {"object": "mobile", "frames": 5,
                               "keyframes": [{"frame": 0, "translate": [340, -338.9, -90]},
                                             {"frame": 3, "translate": [200, -338.9, 35],
                                              "rotate": {"axis": [0, 1, 0], "degrees": 40}}]}},
  "outputs": {"exr": "img.exr", "report": "r.json"}
}
JOB
FRAMES="0000 0001 0002 0003 0004"
untimed() { grep -v '"seconds"' "$1"; }
same_frames() { # same_frames DIR_A DIR_B WHAT
    for f in $FRAMES; do
        cmp "$1/img.$f.exr" "$2/img.$f.exr" || fail "$3: img.$f.exr differs"
        untimed "$1/r.$f.json" >"$TMP/a.json"
        untimed "$2/r.$f.json" >"$TMP/b.json"
        cmp "$TMP/a.json" "$TMP/b.json" || fail "$3: r.$f.json differs"
    done
}
sed 's/"object": "mobile"/"object": "tall_block"/' "$TMP/job.json" >"$TMP/static.json"
st=0
"$GI" validate "$TMP/static.json" >"$TMP/static.out" 2>&1 || st=$?
[ $st -ne 0 ] &&
    grep -q 'quadrature.animation.object: object "tall_block" is not mobile' "$TMP/static.out" ||
    { cat "$TMP/static.out"; fail "a static object was animated: exit $st"; }

"$GI" validate "$SRC/scenes/cornell-box/quadrature-animation.json" >"$TMP/example.out" 2>&1 ||
    { cat "$TMP/example.out"; fail "validate the example"; }
render "$TMP/job.json" "$TMP/w1" 1
render "$TMP/job.json" "$TMP/w3" 3
same_frames "$TMP/w1" "$TMP/w3" "1 vs 3 workers"
# Round 0 is 4 tasks (256 regions); a crash in frame 0's round 0 and one
# in a later round.
GI_FAULT_CRASH_TASK="1:0,6:0" render "$TMP/job.json" "$TMP/crash" 2
grep -q "retried (2 worker crashes)" "$TMP/crash.log" ||
    { cat "$TMP/crash.log"; fail "crashes not reported"; }
same_frames "$TMP/w1" "$TMP/crash" "after injected crashes"
for f in 0000 0001 0003; do
    grep -q "\"frame\":[[:space:]]*${f#000}," "$TMP/w1/r.$f.json" || fail "r.$f.json: no frame"
    grep -q '"rounds":[[:space:]]*\([2-9]\|[1-9][0-9]\)' "$TMP/w1/r.$f.json" ||
        fail "r.$f.json: refined no round past 0"
done
grep -q '"pose":' "$TMP/w1/r.0002.json" || fail "no pose in the report"

# Frame 3 is the still of its key's pose; frame 4 holds it.
sed -e 's/"frames": 5,/"frames": 1,/' -e 's/{"frame": 0, "translate": \[340, -338.9, -90\]},//' \
    -e 's/{"frame": 3,/{"frame": 0,/' "$TMP/job.json" >"$TMP/pose3.json"
render "$TMP/pose3.json" "$TMP/pose3" 2
cmp "$TMP/pose3/img.0000.exr" "$TMP/w1/img.0003.exr" || fail "frame 3 is not the still of its pose"
cmp "$TMP/w1/img.0003.exr" "$TMP/w1/img.0004.exr" || fail "the held frame 4 differs from frame 3"
if cmp -s "$TMP/w1/img.0000.exr" "$TMP/w1/img.0001.exr"; then fail "frames 0 and 1 are the same"; fi

# Frame 2's image cannot be written (a directory in its way): the render
# fails naming it and keeps the frame; --resume writes it and the rest.
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
same_frames "$TMP/w1" "$TMP/blocked" "resumed after a blocked write"
# A camera path, nothing moving: frame 1, at its key, is the still seen
# from that key's camera (the job's "camera"), image and report.
write_job "$TMP/cam.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "quadrature",
 "image": {"width": 32, "height": 32},
 "quadrature": {"dims": 4, "max_evals": 300000,
                "animation": {"frames": 2, "camera": [
                  {"frame": 1, "position": [100, 300, -600], "look_at": [278, 200, 300],
                   "fov_y": 50}]}},
 "outputs": {"exr": "img.exr", "report": "r.json"}}
JOB
write_job "$TMP/cam-still.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "quadrature",
 "image": {"width": 32, "height": 32},
 "camera": {"position": [100, 300, -600], "look_at": [278, 200, 300], "fov_y": 50},
 "quadrature": {"dims": 4, "max_evals": 300000}, "outputs": {"exr": "still.exr"}}
JOB
render "$TMP/cam.json" "$TMP/cam" 2
render "$TMP/cam-still.json" "$TMP/cam-still" 1
cmp "$TMP/cam/img.0001.exr" "$TMP/cam-still/still.exr" ||
    fail "the camera path's frame 1 is not the still from its key's camera"
cmp "$TMP/cam/img.0000.exr" "$TMP/cam/img.0001.exr" || fail "frame 0 does not hold the first key"
echo "quadrature animation frames identical: 1/3 workers, crashes, still of the pose, held, resumed; camera path"
