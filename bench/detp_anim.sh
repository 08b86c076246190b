#!/bin/sh
# detp_anim: full recompute vs incremental frame of a detp animation
# (issue 7). The thesis's Table A.14: the Cornell box with a mobile sphere of
# radius 1.25% ... 50% of the box's width (gi_scenegen cornell-mobile), clear
# of the walls and blocks up to 27%, moving 1% of the width (5.56 mm) along x
# per frame;
# the 10% case again with "update": "full" and with the Sphere Cache and
# Embree for the mobile's vertices; and the tree scene (gi_scenegen tree) with its
# 500-triangle torus moving 0.01 (1% of the scene) along x per frame. One
# worker (`gi render --workers 1`), "json" output only. ROUNDS rounds, each
# running every case once in a rotated order; bench/anim_frames prints the
# medians (see its header for what "full" and "incremental" sum).
#   bench/detp_anim.sh BUILD_DIR [PHOTONS] [BATCH] [FRAMES] [ROUNDS] [OUT]
# OUT (default bench/out/anim, gitignored) keeps the scenes and reports.
set -eu
BIN=${1:-build/release}
PHOTONS=${2:-1000000}
BATCH=${3:-250000}
FRAMES=${4:-6}
ROUNDS=${5:-3}
SRC=$(cd "$(dirname "$0")/.." && pwd)
OUT=${6:-$SRC/bench/out/anim}
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
RADII="0.0125 0.025 0.05 0.075 0.1 0.125 0.15 0.175 0.2 0.25 0.5"
CASES="$RADII 0.1-full 0.1-sc 0.1-em tree tree-full"
last=$((FRAMES - 1))

# Always written afresh: a scene left in OUT by an older gi_scenegen would
# silently measure another room.
for f in $RADII; do
    "$BIN/scenes/gi_scenegen" cornell-mobile "$SRC/scenes/cornell-box/scene.json" \
        "$OUT/scene-$f.json" --radius "$f" >/dev/null
done
[ -f "$OUT/tree/scene.json" ] || { mkdir -p "$OUT/tree" &&
    "$BIN/scenes/gi_scenegen" tree "$OUT/tree" >/dev/null; }

# job CASE FILE: the case's job.
job() {
    case $1 in
    tree*) scene=$OUT/tree/scene.json step=0.01 extra='"radius": "1%"' ;;
    *) scene=$OUT/scene-${1%%-*}.json step=5.56 extra='"subdivide": 20, "radius": "auto"' ;;
    esac
    anim=
    case $1 in
    *-full) anim=', "update": "full"' ;;
    *-sc) anim=', "mobile_estimator": "sphere_cache"' ;;
    *-em) anim=', "mobile_estimator": "embree"' ;;
    esac
    cat >"$2" <<JOB
{"scene": "$scene", "method": "detp", "seed": 1, "image": {"width": 64, "height": 64},
 "detp": {"photons": $PHOTONS, "batch": $BATCH, $extra, "estimator": "embree",
          "animation": {"object": "mobile", "frames": $FRAMES$anim,
            "keyframes": [{"frame": 0, "translate": [0, 0, 0]},
                          {"frame": $last, "translate": [$(awk "BEGIN { print $step * $last }"), 0, 0]}]}},
 "outputs": {"json": "r.json"}}
JOB
}

n=$(echo $CASES | wc -w)
r=0
while [ $r -lt "$ROUNDS" ]; do
    # Rotate the order by a third of the cases each round.
    i=0
    for c in $CASES $CASES; do
        i=$((i + 1))
        [ $i -gt $((r * n / 3 % n)) ] && [ $i -le $((r * n / 3 % n + n)) ] || continue
        d=$OUT/r$r/$c
        mkdir -p "$d"
        job "$c" "$d/job.json"
        "$BIN/gi" render "$d/job.json" --workers 1 --out "$d" --progress none >"$d/log" 2>&1 ||
            { cat "$d/log"; exit 1; }
    done
    r=$((r + 1))
done

runs() { r=0; while [ $r -lt "$ROUNDS" ]; do printf '%s ' "$OUT/r$r/$1/r"; r=$((r + 1)); done; }
echo "photons $PHOTONS, batch $BATCH, frames $FRAMES, medians of $ROUNDS rounds, one worker"
"$BIN/bench/anim_frames" header
for f in $RADII; do
    # shellcheck disable=SC2046
    "$BIN/bench/anim_frames" row "$(awk "BEGIN { print 100 * $f }")%" "$f" "$FRAMES" $(runs "$f")
done
"$BIN/bench/anim_frames" row '10%, "update": "full"' 0.1 "$FRAMES" $(runs 0.1-full)
"$BIN/bench/anim_frames" row '10%, Sphere Cache mobile' 0.1 "$FRAMES" $(runs 0.1-sc)
"$BIN/bench/anim_frames" row '10%, Embree mobile' 0.1 "$FRAMES" $(runs 0.1-em)
"$BIN/bench/anim_frames" row 'tree, torus' 0 "$FRAMES" $(runs tree)
"$BIN/bench/anim_frames" row 'tree, torus, "update": "full"' 0 "$FRAMES" $(runs tree-full)
echo
"$BIN/bench/anim_frames" phase_header
for c in 0.0125 0.025 0.1 0.1-full 0.1-sc 0.1-em 0.5 tree tree-full; do
    "$BIN/bench/anim_frames" phases "$c" "$FRAMES" $(runs "$c")
done
