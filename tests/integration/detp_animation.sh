# detp animation (issue 7) with `gi render`: every frame's outputs are
# byte-identical with 1 and 3 workers, with "update": "full" (every vertex
# recomputed over the frame's segments: the incremental sums must equal
# it exactly), after injected crashes of batch updates and tiles (retries
# find their input in the store), and after the batch store is wiped in the
# middle of the animation (batches regenerated from their seeds). Frames
# after the first retrace some paths, not all; the batch directory is gone
# at the end.
. "$(dirname "$0")/lib.sh"
mkdir -p "$TMP/tmp"
export TMPDIR="$TMP/tmp"
write_job "$TMP/job.json" <<JOB
{
  "scene": "$SRC/scenes/cornell-box/scene-mobile.json",
  "method": "detp",
  "seed": 5,
  "image": {"width": 32, "height": 32},
  "detp": {"photons": 48000, "batch": 6000, "subdivide": 60, "tile": 16, "image_spp": 1,
           "animation": {"object": "mobile", "frames": 6,
                         "keyframes": [{"frame": 0, "translate": [340, -338.9, -90]},
                                       {"frame": 5, "translate": [268, -338.9, -20.4],
                                        "rotate": {"axis": [0, 1, 0], "degrees": 40}}]}},
  "outputs": {"exr": "img.exr", "ply": "v.ply", "bin": "v.bin", "json": "report.json"}
}
JOB
same_frames() { # same_frames DIR_A DIR_B WHAT
    for f in 0000 0001 0002 0003 0004 0005; do
        for k in img.$f.exr v.$f.ply v.$f.bin; do
            cmp "$1/$k" "$2/$k" || fail "$3: $k differs"
        done
    done
}
# A key that puts the mobile wholly outside the room is validated with a
# warning naming it (units or a sign gone wrong); the job's own keys, none.
"$GI" validate "$TMP/job.json" >/dev/null 2>"$TMP/validate.err" || fail "validate"
# (Its discs are coarse, 6% of the scene, and validate says that too.)
! grep -q "keyframes" "$TMP/validate.err" || { cat "$TMP/validate.err"; fail "the job's keys were warned about"; }
sed 's/"translate": \[268, -338.9, -20.4\]/"translate": [268, -338.9, -2000]/' "$TMP/job.json" >"$TMP/away.json"
"$GI" validate "$TMP/away.json" >/dev/null 2>"$TMP/away.err" || fail "validate away"
grep -q "detp.animation.keyframes\[1\]: at frame 5 the mobile lies wholly outside" "$TMP/away.err" ||
    { cat "$TMP/away.err"; fail "a key outside the room was not warned about"; }
render "$TMP/job.json" "$TMP/w1" 1
render "$TMP/job.json" "$TMP/w3" 3 json
same_frames "$TMP/w1" "$TMP/w3" "1 vs 3 workers"
# Progress counts the frames, and the job's fraction never goes back when a
# frame's tasks or its image tiles are planned.
grep '"event":"progress"' "$TMP/w3.log" | awk '
    { match($0, /"fraction":[0-9.]*/); f = substr($0, RSTART + 11, RLENGTH - 11) + 0 }
    f < last { print "fraction went back: " last " then " f; bad = 1 }
    { last = f }
    /"frame":5,"frames":6/ && f == 1 { end = 1 }
    END { if (!end) print "no last frame at 100%"; exit bad || !end }' ||
    { cat "$TMP/w3.log"; fail "progress of the animation"; }

sed 's/"frames": 6,/"frames": 6, "update": "full",/' "$TMP/job.json" >"$TMP/full.json"
render "$TMP/full.json" "$TMP/full" 2
same_frames "$TMP/w1" "$TMP/full" "incremental vs full recompute"

# Rule 1 with nothing behind a hit: the segments that hit this panel's top
# reach on without end, through the ball below it (crossing its discs,
# and their t_second is the ball's whenever it passes under). The batch
# grid must list them there too: a frame that did not read them would
# miss the ball's crossings that a full recompute counts.
cat >"$TMP/open.json" <<'SCENE'
{"materials": {"w": {"diffuse": [0.6, 0.6, 0.6]},
               "l": {"diffuse": [0, 0, 0], "emission": [4, 4, 4]}},
 "objects": [
  {"name": "ball", "material": "w", "mobile": true,
   "sphere": {"radius": 0.3, "subdivisions": 2},
   "transform": [{"translate": [-0.6, -1, 0]}]},
  {"name": "panel", "material": "w", "quad": {"size": [3, 3]}},
  {"name": "lamp", "material": "l", "quad": {"size": [1, 1]},
   "transform": [{"rotate": {"axis": [1, 0, 0], "degrees": 180}}, {"translate": [0, 1.5, 0]}]}]}
SCENE
write_job "$TMP/open-job.json" <<JOB
{"scene": "$TMP/open.json", "method": "detp", "seed": 3, "image": {"width": 16, "height": 16},
 "detp": {"photons": 20000, "batch": 5000, "radius": "2%",
          "animation": {"object": "ball", "frames": 6,
                        "keyframes": [{"frame": 0, "translate": [0, 0, 0]},
                                      {"frame": 5, "translate": [1.2, 0, 0.2]}]}},
 "outputs": {"bin": "v.bin"}}
JOB
sed 's/"frames": 6,/"frames": 6, "update": "full",/' "$TMP/open-job.json" >"$TMP/open-full.json"
render "$TMP/open-job.json" "$TMP/open-inc" 1
render "$TMP/open-full.json" "$TMP/open-full" 1
for f in 0001 0002 0003 0004 0005; do
    cmp "$TMP/open-inc/v.$f.bin" "$TMP/open-full/v.$f.bin" ||
        fail "open scene, frame $f: incremental differs from the full recompute"
done

# Held poses (before the first key, between equal keys, after the last):
# nothing is retraced and the frames are the same bits, no flicker.
sed -e 's/"frames": 6,/"frames": 7,/' \
    -e 's/{"frame": 0, "translate": \[0, 0, 0\]}/{"frame": 1, "translate": [0, 0, 0]}, {"frame": 3, "translate": [0, 0, 0]}/' \
    -e 's/{"frame": 5, "translate": \[1.2, 0, 0.2\]}/{"frame": 5, "translate": [1.2, 0, 0.2]}/' \
    -e 's/"outputs": {"bin": "v.bin"}/"outputs": {"bin": "v.bin", "exr": "i.exr", "json": "r.json"}/' \
    "$TMP/open-job.json" >"$TMP/held.json"
grep -q '"frame": 3' "$TMP/held.json" || fail "held job not made"
render "$TMP/held.json" "$TMP/held" 2
for pair in 0000:0001 0001:0002 0002:0003 0005:0006; do
    a=${pair%:*} b=${pair#*:}
    cmp "$TMP/held/v.$a.bin" "$TMP/held/v.$b.bin" && cmp "$TMP/held/i.$a.exr" "$TMP/held/i.$b.exr" ||
        fail "held frames $a and $b differ"
    grep -q '"paths_retraced":[[:space:]]*0,' "$TMP/held/r.$b.json" || fail "held frame $b retraced paths"
done
if cmp -s "$TMP/held/v.0003.bin" "$TMP/held/v.0004.bin"; then fail "moving frames 3 and 4 are the same"; fi

# The frames differ (the sphere moves), and later frames retraced a part.
if cmp -s "$TMP/w1/v.0000.bin" "$TMP/w1/v.0005.bin"; then fail "frames 0 and 5 are the same"; fi
for f in 0001 0003 0005; do
    r="$TMP/w1/report.$f.json"
    tested=$(sed -n 's/.*"paths_tested":[^0-9]*\([0-9]*\).*/\1/p' "$r")
    retraced=$(sed -n 's/.*"paths_retraced":[^0-9]*\([0-9]*\).*/\1/p' "$r")
    [ "$tested" = 48000 ] || fail "frame $f: $tested paths tested"
    [ "$retraced" -gt 0 ] && [ "$retraced" -lt $((tested / 5)) ] ||
        fail "frame $f: $retraced of $tested paths retraced"
done
[ -z "$(ls "$TMPDIR")" ] || { ls -R "$TMPDIR"; fail "batch directory left behind"; }

# Crashes: frame 0 has batch tasks 0-7 and tiles 8-11, frame 1 updates
# 12-19 and tiles 20-23, frame 2 updates 24-31, ...
GI_FAULT_CRASH_TASK="13:0,21:0,26:0,26:1,38" render "$TMP/job.json" "$TMP/hook" 2
grep -q "retried (5 worker crashes)" "$TMP/hook.log" || { cat "$TMP/hook.log"; fail "crashes not reported"; }
same_frames "$TMP/w1" "$TMP/hook" "after injected crashes"

# The store wiped while frame 2 or 3 runs: later updates regenerate.
sed -e 's/"photons": 48000/"photons": 400000/' -e 's/"batch": 6000/"batch": 50000/' \
    "$TMP/job.json" >"$TMP/long.json"
"$GI_RELEASE" render "$TMP/long.json" --workers 2 --out "$TMP/long-ref" --progress none \
    >/dev/null 2>&1 || fail "long reference"
"$GI_RELEASE" render "$TMP/long.json" --workers 2 --out "$TMP/long-wipe" --progress none \
    >"$TMP/long-wipe.log" 2>&1 &
pid=$!
wiped=0
for i in $(seq 1 400); do
    if ls "$TMPDIR"/gi-render-*/*/b*.f2.* >/dev/null 2>&1; then
        rm -f "$TMPDIR"/gi-render-*/*/b*
        wiped=1
        break
    fi
    sleep 0.05
done
wait $pid || { cat "$TMP/long-wipe.log"; fail "render with a wiped store"; }
[ $wiped = 1 ] || fail "never saw frame 2's files"
regen=0
for r in "$TMP"/long-wipe/report.000*.json; do
    n=$(sed -n 's/.*"frames_regenerated":[^0-9]*\([0-9]*\).*/\1/p' "$r")
    regen=$((regen + n))
done
[ "$regen" -gt 0 ] || fail "no batch was regenerated after the wipe"
for f in 0000 0001 0002 0003 0004 0005; do
    for k in img.$f.exr v.$f.bin; do
        cmp "$TMP/long-ref/$k" "$TMP/long-wipe/$k" || fail "$k differs after the store was wiped"
    done
done
echo "animation frames identical: 1/3 workers, full recompute, crashes, wiped store ($regen frames regenerated)"
