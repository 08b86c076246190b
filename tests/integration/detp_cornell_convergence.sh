# detp on the Cornell box converges to the path tracer's irradiance at the
# same vertices (gi_pt_irradiance, 2048 samples each at 150 vertices) as
# photons grow 4x and the disc radius shrinks by sqrt(2) per step: the mean
# absolute difference over the mean irradiance falls at every step, ending
# within a few percent (the reference's own noise is ~2%), with no overall
# bias. Prints the table (bench/BENCHMARKS.md has a longer one).
. "$(dirname "$0")/lib.sh"
prev=1
step=0
echo "photons radius_mm mean_abs_diff/mean mean_rel_error bias_of_mean pt_rel_stderr"
for cfg in "50000 40" "200000 28" "800000 20"; do
    set -- $cfg
    step=$((step + 1))
    write_job "$TMP/c$step.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "detp", "seed": 3,
 "detp": {"photons": $1, "batch": 100000, "subdivide": 20, "radius": $2,
          "reference": {"spp": 2048, "vertices": 150}},
 "outputs": {"json": "r.json"}}
JOB
    "$GI_RELEASE" render "$TMP/c$step.json" --workers 2 --out "$TMP/o$step" --progress none \
        >/dev/null || fail "render $cfg"
    r="$TMP/o$step/r.json"
    field() { sed -n "s/^[[:space:]]*\"$1\":[[:space:]]*\([-0-9.e]*\),*$/\1/p" "$r" | head -n 1; }
    dev=$(field mean_abs_error_over_mean)
    rel=$(field mean_abs_relative_error)
    bias=$(field relative_error_of_mean)
    se=$(field pt_mean_relative_stderr)
    echo "$1 $2 $dev $rel $bias $se"
    awk -v d="$dev" -v p="$prev" -v b="$bias" 'BEGIN { exit !(d < p && b < 0.03 && b > -0.03) }' ||
        fail "step $step: error $dev (previous $prev), bias $bias"
    prev=$dev
done
awk -v d="$prev" 'BEGIN { exit !(d < 0.04) }' || fail "final error $prev is not below 4%"
echo ok
