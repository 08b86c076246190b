#!/bin/sh
# make bench: runs every benchmark driver and prints its table. Numbers are
# recorded by hand in bench/BENCHMARKS.md with the command that made them.
#   bench/run.sh BUILD_DIR
set -eu
BIN=${1:-build/release}
SRC=$(cd "$(dirname "$0")/.." && pwd)
cd "$SRC"
echo "== pt_vs_embree: path tracer vs bare Embree on the same rays (one core)"
"$BIN/bench/pt_vs_embree" scenes/cornell-box/scene.json 256 8 9
echo "== pt_vs_embree on a heavier scene (Cornell box + 163,840 sphere triangles)"
"$BIN/bench/pt_vs_embree" bench/scenes/cornell-spheres.json 256 8 9
echo "== detp_tree: thesis Tables A.2-A.4 on a generated tree scene (one core; minutes)"
TREE=$(mktemp -d "${TMPDIR:-/tmp}/detp-tree.XXXXXX")
"$BIN/scenes/gi_scenegen" tree "$TREE"
"$BIN/bench/detp_tree" "$TREE/scene.json" 409600 3
echo "== detp_disc_order: Embree Disc Indexing with the discs numbered as the mesh, along a Hilbert curve, shuffled"
"$BIN/bench/detp_disc_order" scenes/cornell-box/scene.json 4 0 1000000 5
echo "== anim_rt: moving the tree scene's torus (update_object, one incremental frame vs full retrace)"
"$BIN/bench/anim_rt" "$TREE/scene.json" 400000 21
rm -rf "$TREE"
echo "== detp_memory: peak RSS of detp bakes on the Cornell box (2 workers; minutes)"
sh bench/detp_memory.sh "$BIN" 5000000 50000000
echo "== detp_anim: thesis Table A.14 + the tree's torus, full vs incremental frame (one worker; ~15 min)"
sh bench/detp_anim.sh "$BIN" 1000000 250000 6 3
echo "== detp_anim_image: a 1080p animation with EXR + PNG outputs (2 workers): tiles and writes per frame"
sh bench/detp_anim_image.sh "$BIN" 24 1920 1080
echo "== detp_anim_memory: 100 M photon paths, moving sphere, 2 workers: peak RSS and batch disk (TMPDIR needs ~13 GB; ~11 min)"
sh bench/detp_anim_memory.sh "$BIN" 100000000 3 250000
echo "== anim_vs_still: 24-frame pt and quadrature animations, detp and radiosity walk-throughs against their stills (2 workers; ~4 min)"
sh bench/anim_vs_still.sh "$BIN" scenes/cornell-box/pt-animation.json 3 2
sh bench/anim_vs_still.sh "$BIN" scenes/cornell-box/quadrature-animation.json 3 2
sh bench/anim_vs_still.sh "$BIN" scenes/cornell-box/detp-flythrough.json 3 2
sh bench/anim_vs_still.sh "$BIN" scenes/cornell-box/radiosity-flythrough.json 3 2
echo "== resume_anim: gi render --resume of a 24-frame animation stopped at frame 16 (4 M photons; ~1 min)"
sh bench/resume_anim.sh "$BIN" 4000000 500000 24 16
echo "== mesh_import: gi validate on a 25 MB OBJ (980k triangles; assimp in a child process)"
sh bench/mesh_import.sh "$BIN" 700 5
echo "== many_objects: scene load and tiny renders of 1k, 10k, 100k cubes (gi_scenegen grid; ~5 min)"
sh bench/many_objects.sh "$BIN" "1000 10000 100000" 3 "" \
    "validate validate-mesh pt detp quadrature radiosity"
echo "== many_objects: 1k, 10k cubes, each a mesh file of its own: validate, tiny pt (~3 min)"
sh bench/many_objects.sh "$BIN" "1000 10000" 3 "" "validate-files pt-files"
echo "== rt_build: the Embree build of 100,000 cubes, by geometry layout and build quality"
G=$(mktemp -d "${TMPDIR:-/tmp}/gi-bench-grid.XXXXXX")
"$BIN/scenes/gi_scenegen" grid "$G" --objects 100000
"$BIN/bench/rt_build" "$G/scene.json" 3
rm -rf "$G"
echo "== farm_overhead: a job through gi-farmd + gi-worker (2 processes, loopback) vs gi render --workers 2"
sh bench/farm_overhead.sh "$BIN" 5
echo "== quad_genz: adaptive cubature on Genz's test families (evaluations for 1e-3 and 1e-6)"
"$BIN/bench/quad_genz" 6 2e7
echo "== quad_heap: bucketed vs binary vs pairing heap (median of 9 alternating rounds)"
"$BIN/bench/quad_heap" 2000000 9
echo "== quad_vs_pt: quadrature vs path tracer at equal time on the Cornell box (references cached in out/bench)"
"$BIN/bench/quad_vs_pt" scenes/cornell-box/scene.json out/bench 16384 3

echo "== rad_form_factors: ray-cast form factors against closed forms (radiosity)"
"$BIN/bench/rad_form_factors"
echo "== rad_relight: time per RGB relight, the thesis's Table 4.7 cases (radiosity)"
"$BIN/bench/rad_relight" 15 1-9
echo "== rad_build: factorization build (gi render, 2 workers) for n = 13824 and 55296, k = 864"
work=$(mktemp -d "${TMPDIR:-/tmp}/gi-bench.XXXXXX")
"$BIN/bench/rad_scene" "$work/room.json" 4 2 0.25
for levels in 3 4; do
    cat >"$work/build$levels.json" <<JOB
{"scene": "room.json", "method": "radiosity",
 "radiosity": {"patches": 216, "levels": $levels, "patch_level": 1, "rays": 1024},
 "outputs": {"factorization": "room$levels.fact", "report": "room$levels.json"}}
JOB
    "$BIN/gi" render "$work/build$levels.json" --workers 2 --out "$work" --progress none
    grep -A2 '"timings_ms"' "$work/room$levels.json"
done
rm -rf "$work"
echo "== rad_factorizations: Table 4.2 (radiosity error vs the dense solve), two scenes"
"$BIN/bench/rad_factorizations" room 1024 70
"$BIN/bench/rad_factorizations" scenes/cornell-box/scene.json 1024 70
echo "== rad_moving: moving object, Algorithm 6 + double SMW"
"$BIN/bench/rad_moving" 1024 70
echo "== result_check: the coordinator's check of a worker result beside its merge (CPU time a task)"
rc_out=$(mktemp -d "${TMPDIR:-/tmp}/result-check.XXXXXX")
for job in pt-default detp-default detp-animation-batches quadrature-default radiosity-default; do
    "$BIN/bench/result_check" "bench/scale/$job.json" "$rc_out/$job"
done
rm -rf "$rc_out"
