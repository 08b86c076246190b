#!/bin/sh
# many_objects: what a scene of many small objects costs to load and render.
# For each N, `gi_scenegen grid` writes N cubes (12 triangles each) in a lit
# room, and this times, in seconds (wall clock; median of ROUNDS):
#   validate       gi validate of the scene (JSON, assembly, checks)
#   validate-mesh  the same with every cube a reference to one cube.obj
#   validate-files the same with every cube a mesh file of its own (N OBJs)
#   pt-files       gi render --workers 1 of the tiny pt job below on that scene
#   pt, detp, quadrature, radiosity
#                  gi render --workers 1 of a tiny job of each method (a
#                  32 x 32 image, 1 sample / 2,000 photons / small budgets),
#                  where the per-object and per-triangle costs dominate
# Radiosity refuses scenes over its element limit: that is printed as
# "refused" with the first line of its message.
# With a second gi, the two alternate (e.g. a build from before a change);
# its column is the second figure.
#   bench/many_objects.sh BUILD_DIR "N1 N2 ..." [ROUNDS] [OTHER_GI] [STEPS]
# STEPS (default all): a subset of "validate validate-mesh validate-files pt-files pt detp
# quadrature radiosity".
set -eu
BIN=${1:-build/release}
SIZES=${2:-1000 10000 100000}
ROUNDS=${3:-3}
OTHER=${4:-}
STEPS=${5:-validate validate-mesh validate-files pt-files pt detp quadrature radiosity}
T=$(mktemp -d "${TMPDIR:-/tmp}/gi-bench-many.XXXXXX")
trap 'rm -rf "$T"' EXIT INT TERM
now() { date +%s.%N; }
median() { sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }

job() { # METHOD [SCENE] -> a job file for it (SCENE: default scene.json)
    case $1 in
    pt) params='"pt": {"spp": 1, "tile": 32}' ;;
    detp) params='"detp": {"photons": 2000, "batch": 1000, "tile": 32}' ;;
    quadrature) params='"quadrature": {"max_evals": 20000}' ;;
    radiosity) params='"radiosity": {"patches": 16, "levels": 1, "rays": 16}' ;;
    esac
    printf '{"scene": "%s", "method": "%s", "seed": 1, "image": {"width": 32, "height": 32},\n %s, "outputs": {"exr": "t.exr"}}\n' \
        "${2:-scene.json}" "$1" "$params"
}

# run GI STEP DIR -> seconds on stdout, or "refused: ..." when gi failed
run() {
    gi=$1 step=$2 dir=$3
    case $step in
    validate) set -- "$gi" validate "$dir/scene.json" ;;
    validate-mesh) set -- "$gi" validate "$dir/mesh/scene.json" ;;
    validate-files) set -- "$gi" validate "$dir/files/scene.json" ;;
    *) set -- "$gi" render "$dir/$step.json" --workers 1 --out "$dir/out" --progress none ;;
    esac
    t0=$(now)
    if "$@" >"$dir/log" 2>&1; then
        awk -v a="$t0" -v b="$(now)" 'BEGIN {print b - a}'
    else
        echo "refused: $(tail -n 1 "$dir/log" | sed "s|$dir/||")"
    fi
}

for n in $SIZES; do
    d="$T/n$n"
    "$BIN/scenes/gi_scenegen" grid "$d" --objects "$n"
    "$BIN/scenes/gi_scenegen" grid "$d/mesh" --objects "$n" --mesh
    case $STEPS in *-files*)
        "$BIN/scenes/gi_scenegen" grid "$d/files" --objects "$n" --mesh-files ;;
    esac
    for m in pt detp quadrature radiosity; do job $m >"$d/$m.json"; done
    job pt files/scene.json >"$d/pt-files.json"
    echo "N = $n: $(wc -c <"$d/scene.json") bytes of scene, $((12 * n + 14)) triangles"
    for step in $STEPS; do
        : >"$T/a"
        : >"$T/b"
        i=0
        while [ $i -lt "$ROUNDS" ]; do
            r=$(run "$BIN/gi" "$step" "$d")
            case $r in refused*) echo "  $step: $r"; break ;; esac
            echo "$r" >>"$T/a"
            [ -z "$OTHER" ] || run "$OTHER" "$step" "$d" >>"$T/b"
            i=$((i + 1))
        done
        [ -s "$T/a" ] || continue
        line=$(printf '  %-14s %8.3f' "$step" "$(median <"$T/a")")
        if [ -n "$OTHER" ]; then
            if grep -q refused "$T/b"; then
                line="$line   other: $(grep -m 1 refused "$T/b")"
            else
                line="$line   other: $(printf '%.3f' "$(median <"$T/b")")"
            fi
        fi
        echo "$line"
    done
done
