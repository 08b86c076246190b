#!/bin/sh
# detp_anim_ab: compare builds on one detp animation job (issue 7), the
# runs alternated so that the machine's drift falls on every build alike.
# Each run renders JOB with one worker; per build, the minimum and the
# median over the rounds of the mean incremental phases (frames 1..):
# test_and_retrace, static_update, mobile_vertices, store_write, their sum.
#   bench/detp_anim_ab.sh JOB ROUNDS GI_BINARY...
# JOB must write its report with "outputs": {"json": "r.json"}.
set -eu
[ $# -ge 3 ] || { echo "usage: $0 JOB ROUNDS GI_BINARY..." >&2; exit 2; }
job=$1
rounds=$2
shift 2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
r=0
while [ "$r" -lt "$rounds" ]; do
    for b in "$@"; do
        rm -rf "$tmp/out"
        "$b" render "$job" --workers 1 --out "$tmp/out" --progress none >"$tmp/log" 2>&1 ||
            { cat "$tmp/log"; exit 1; }
        python3 - "$b" "$tmp/out" >>"$tmp/rows" <<'PY'
import glob, json, sys
files = sorted(glob.glob(sys.argv[2] + "/r.*.json"))[1:]
keys = ["test_and_retrace", "static_update", "mobile_vertices", "store_write"]
t = [sum(json.load(open(f))["animation"]["seconds"][k] for f in files) / len(files) for k in keys]
print(sys.argv[1], *["%.5f" % x for x in t + [sum(t)]])
PY
    done
    r=$((r + 1))
done
python3 - "$tmp/rows" <<'PY'
import statistics, sys
rows = {}
for line in open(sys.argv[1]):
    p = line.split()
    rows.setdefault(p[0], []).append([float(x) for x in p[1:]])
print("build: test_and_retrace static_update mobile_vertices store_write sum (s a frame)")
for b, v in rows.items():
    cols = list(zip(*v))
    print(b, "min", " ".join("%.5f" % min(c) for c in cols))
    print(b, "med", " ".join("%.5f" % statistics.median(c) for c in cols))
PY
