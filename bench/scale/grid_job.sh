#!/bin/sh
# A pt job on a scene with one large mesh (an N x N grid of quads as an OBJ:
# N=300 gives 4.3 MB), for the coordinator's cost of sending assets to hosts:
#   sh bench/scale/grid_job.sh DIR [N]; bench/farm_scale.sh BUILD W DIR/job.json DIR/job.json
# (the second run finds the workers' caches warm: the difference is the fetches).
set -eu
D=${1:?DIR}
N=${2:-300}
mkdir -p "$D"
sh "$(dirname "$0")/../grid_obj.sh" "$N" >"$D/grid.obj"
cat >"$D/scene.json" <<'SCENE'
{"camera": {"position": [0.5, 2, 0.5], "look_at": [0.5, 0, 0.5], "up": [0, 0, 1], "fov_y": 40},
 "materials": {"w": {"diffuse": [0.5, 0.5, 0.5]}, "l": {"emission": [1, 1, 1]}},
 "objects": [{"name": "grid", "material": "w", "mesh": "grid.obj"},
             {"name": "lamp", "material": "l", "quad": {"size": [0.2, 0.2]},
              "transform": [{"rotate": {"axis": [1, 0, 0], "degrees": 180}},
                            {"translate": [0.5, 1, 0.5]}]}]}
SCENE
cat >"$D/job.json" <<'JOB'
{"scene": "scene.json", "method": "pt", "image": {"width": 256, "height": 256},
 "pt": {"spp": 1, "tile": 16}, "outputs": {"exr": "t.exr"}}
JOB
