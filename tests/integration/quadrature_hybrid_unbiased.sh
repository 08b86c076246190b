# The hybrid estimator (quadrature of the first N = 4 coordinates, Monte
# Carlo with the region interpolants as control variates for what the
# quadrature left open and for every coordinate beyond N) is unbiased: the
# mean of 64 seeds matches the path tracer's full global illumination within
# 3 standard errors in every 8 x 8 block. The reference is independent of
# the method under test: 16 path tracer runs (MIS, Russian roulette, its own
# sampling maps), whose spread gives its standard errors. The same
# quadrature without the Monte Carlo phase (paths cut at N: direct light
# only) fails the comparison.
. "$(dirname "$0")/lib.sh"
BS="$BUILD/release/tools/gi_blockstats"
refs=""
for s in $(seq 101 116); do
    write_job "$TMP/pt$s.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "pt", "seed": $s,
 "image": {"width": 32, "height": 32}, "pt": {"spp": 512},
 "outputs": {"exr": "pt$s.exr"}}
JOB
    "$GI_RELEASE" render "$TMP/pt$s.json" --workers 2 --out "$TMP" --progress none >/dev/null ||
        fail "pt reference $s"
    refs="$refs $TMP/pt$s.exr"
done
job() { # name seed hybrid
    write_job "$TMP/$1.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "quadrature", "seed": $2,
 "image": {"width": 32, "height": 32},
 "quadrature": {"dims": 4, "rule": "genz-malik", "max_evals": 60000, "threshold": 1e-6,
                "hybrid": $3 $( [ "$3" = true ] && echo ', "mc_spp": 4') },
 "outputs": {"exr": "$1.exr", "report": "$1.report"}}
JOB
    "$GI_RELEASE" render "$TMP/$1.json" --workers 2 --out "$TMP" --progress none >/dev/null ||
        fail "render $1"
}
runs=""
for s in $(seq 1 64); do
    job "h$s" "$s" true
    runs="$runs $TMP/h$s.exr"
done
grep -q '"regions_closed":	[1-9]' "$TMP/h1.report" || fail "no region closed: the test covers less"
grep -q '"regions_open":	[1-9]' "$TMP/h1.report" || fail "no region left open"
"$BS" 8 3 $refs -- $runs || fail "the hybrid's mean is off the reference"
job cut 1 false
if "$BS" 8 3 $refs -- "$TMP/cut.exr" >/dev/null; then fail "the cut quadrature matched full GI"; fi
echo ok
