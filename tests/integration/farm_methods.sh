# Every method runs on the farm unchanged: a detp, a quadrature, a
# radiosity job, pt and quadrature animations and detp and radiosity camera
# paths (the light seen from each frame's camera) through gi-farmd + one
# gi-worker (2 processes, loopback) give byte-identical outputs to `gi
# render` (the animations' every frame, reports' timings aside). This also carries the data methods
# publish for their image tiles (detp's per-vertex radiance, radiosity's
# element radiosity) through the worker's asset fetch, and detp's across a
# kill -9 and restart of the coordinator (re-published after the restore).
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
S="$SRC/scenes/cornell-box/scene.json"
write_job "$TMP/detp.json" <<JOB
{"scene": "$S", "method": "detp", "seed": 3, "image": {"width": 48, "height": 48},
 "detp": {"photons": 400000, "batch": 10000, "subdivide": 40, "radius": "auto"},
 "outputs": {"exr": "detp.exr", "ply": "detp.ply", "bin": "detp.bin"}}
JOB
write_job "$TMP/quad.json" <<JOB
{"scene": "$S", "method": "quadrature", "image": {"width": 48, "height": 48},
 "quadrature": {"dims": 4, "rule": "boole", "max_evals": 400000},
 "outputs": {"exr": "quad.exr", "report": "quad-report.json"}}
JOB
write_job "$TMP/rad.json" <<JOB
{"scene": "$S", "method": "radiosity", "image": {"width": 48, "height": 48},
 "radiosity": {"patches": 40, "levels": 1, "rays": 256},
 "outputs": {"exr": "rad.exr", "ply": "rad.ply", "factorization": "rad.factorization"}}
JOB
write_job "$TMP/ptanim.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene-mobile.json", "method": "pt", "seed": 3,
 "image": {"width": 32, "height": 32},
 "pt": {"spp": 8, "tile": 16, "pass_spp": 4,
        "animation": {"object": "mobile", "frames": 4,
                      "keyframes": [{"frame": 0, "translate": [340, -338.9, -90]},
                                    {"frame": 3, "translate": [248, -338.9, -0.4]}]}},
 "outputs": {"exr": "anim.exr"}}
JOB
write_job "$TMP/quadanim.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene-mobile.json", "method": "quadrature",
 "image": {"width": 32, "height": 32},
 "quadrature": {"dims": 4, "max_evals": 300000,
                "animation": {"object": "mobile", "frames": 3,
                              "keyframes": [{"frame": 0, "translate": [340, -338.9, -90]},
                                            {"frame": 2, "translate": [248, -338.9, -0.4]}]}},
 "outputs": {"exr": "qanim.exr"}}
JOB
write_job "$TMP/detpcam.json" <<JOB
{"scene": "$S", "method": "detp", "seed": 3, "image": {"width": 32, "height": 32},
 "detp": {"photons": 40000, "batch": 10000, "subdivide": 60, "tile": 16,
          "animation": {"frames": 3, "camera": [
            {"frame": 0, "position": [278, 273, -800], "look_at": [278, 273, 0], "fov_y": 39.3},
            {"frame": 2, "position": [100, 300, -600], "look_at": [278, 200, 300], "fov_y": 50}]}},
 "outputs": {"exr": "cam.exr", "bin": "cam.bin"}}
JOB
write_job "$TMP/radcam.json" <<JOB
{"scene": "$S", "method": "radiosity", "image": {"width": 32, "height": 32},
 "radiosity": {"patches": 40, "levels": 1, "rays": 256, "tile": 16,
               "animation": {"frames": 3, "camera": [{"frame": 0, $CAM_KEY0}, {"frame": 2, $CAM_KEY2}]}},
 "outputs": {"exr": "radcam.exr", "ply": "radcam.ply"}}
JOB
render_refs detp quad rad ptanim quadanim detpcam radcam
[ "$(ls "$TMP/ref-detpcam" | wc -l)" = 4 ] || fail "the detp camera path did not write 3 frames and its light"
[ "$(ls "$TMP/ref-radcam" | wc -l)" = 4 ] || fail "the radiosity camera path did not write 3 frames and its light"
[ "$(ls "$TMP/ref-ptanim" | wc -l)" = 4 ] || fail "the pt animation did not write 4 frames"
[ "$(ls "$TMP/ref-quadanim" | wc -l)" = 3 ] || fail "the quadrature animation did not write 3 frames"

OPTS="--heartbeat 0.2 --lease 5 --dead 20 --checkpoint 0.2"
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$TMP/farmd.log" -- $OPTS
PORTS="--listen-workers $WADDR --listen-api $API"
start_worker "$TMP/worker.log" -- --connect "$WADDR" --procs 2 --cache "$TMP/cache"
for j in quad rad ptanim quadanim detpcam radcam; do
    "$GI" submit "$TMP/$j.json" --wait --out "$TMP/farm-$j" --progress none >"$TMP/$j.log" 2>&1 ||
        { cat "$TMP/$j.log"; fail "farm $j"; }
    for f in "$TMP/ref-$j"/*; do
        case $f in *-report.json) continue ;; esac # its timings differ
        cmp "$f" "$TMP/farm-$j/$(basename "$f")" || fail "$j: $(basename "$f") differs from gi render"
    done
done
# The fetch names each output's kind as the job does, not by its extension.
grep -q "^  report .*/quad-report.json$" "$TMP/quad.log" || { cat "$TMP/quad.log"; fail "quad report's kind"; }
grep -q "^  exr  .*/quad.exr$" "$TMP/quad.log" || { cat "$TMP/quad.log"; fail "quad exr's kind"; }

# detp, with the coordinator killed once a checkpoint holds part of the bake.
id=$("$GI" submit "$TMP/detp.json" 2>"$TMP/submit.log") || { cat "$TMP/submit.log"; fail "submit detp"; }
wait_merged "$id" 4 checkpoint
kill -9 "$FARMD_PID"
wait "$FARMD_PID" 2>/dev/null || true
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$TMP/farmd.log" -- $OPTS $PORTS
wait_state "$id" done 120
"$GI" fetch "$id" --out "$TMP/farm-detp" >/dev/null || fail "fetch detp"
for f in "$TMP/ref-detp"/*; do
    cmp "$f" "$TMP/farm-detp/$(basename "$f")" || fail "detp: $(basename "$f") differs from gi render"
done
stop_farmd "$TMP/farmd.log"
echo "detp, quadrature, radiosity, pt and quadrature animations, detp and radiosity camera paths:" \
    "outputs identical on the farm (detp across a coordinator restart)"
