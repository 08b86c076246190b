#!/bin/sh
# mesh_import: what loading a big mesh costs (`gi validate`: job, scene, the
# mesh through assimp in its child process, the scene checks). Writes an
# N x N grid of quads as OBJ (2 N^2 triangles) and a scene with it and a
# lamp, then times ROUNDS validations and prints the median and the fastest.
# With a second gi, the two alternate (e.g. a build from before a change).
#   bench/mesh_import.sh BUILD_DIR [N] [ROUNDS] [OTHER_GI]
set -eu
BIN=${1:-build/release}
N=${2:-700}
ROUNDS=${3:-5}
OTHER=${4:-}
T=$(mktemp -d "${TMPDIR:-/tmp}/gi-bench-mesh.XXXXXX")
trap 'rm -rf "$T"' EXIT INT TERM
sh "$(dirname "$0")/grid_obj.sh" "$N" >"$T/grid.obj"
cat >"$T/scene.json" <<'SCENE'
{"materials": {"w": {"diffuse": [0.5, 0.5, 0.5]}, "l": {"emission": [1, 1, 1]}},
 "objects": [{"name": "grid", "material": "w", "mesh": "grid.obj"},
             {"name": "lamp", "material": "l", "quad": {"size": [0.2, 0.2]},
              "transform": [{"rotate": {"axis": [1, 0, 0], "degrees": 180}},
                            {"translate": [0.5, 1, 0.5]}]}]}
SCENE
cat >"$T/job.json" <<'JOB'
{"scene": "scene.json", "method": "pt", "image": {"width": 8, "height": 8}, "pt": {"spp": 1},
 "outputs": {"exr": "t.exr"}}
JOB
echo "grid.obj: $(wc -c <"$T/grid.obj") bytes, $((2 * N * N)) triangles"
now() { date +%s.%N; }
median() { sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
"$BIN/gi" validate "$T/job.json" >/dev/null # warm the page cache
: >"$T/a"
: >"$T/b"
i=0
while [ $i -lt "$ROUNDS" ]; do
    t0=$(now)
    "$BIN/gi" validate "$T/job.json" >/dev/null
    t1=$(now)
    awk -v a="$t0" -v b="$t1" 'BEGIN {print b - a}' >>"$T/a"
    if [ -n "$OTHER" ]; then
        "$OTHER" validate "$T/job.json" >/dev/null
        t2=$(now)
        awk -v a="$t1" -v b="$t2" 'BEGIN {print b - a}' >>"$T/b"
    fi
    i=$((i + 1))
done
printf '%s: median %.3f s, fastest %.3f s\n' "$BIN/gi" "$(median <"$T/a")" "$(sort -g "$T/a" | head -n 1)"
[ -z "$OTHER" ] ||
    printf '%s: median %.3f s, fastest %.3f s\n' "$OTHER" "$(median <"$T/b")" "$(sort -g "$T/b" | head -n 1)"
