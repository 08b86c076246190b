# Direct light (N = 4) of the Cornell box converges to the path tracer's
# direct-only image (pt with max_bounces 1): the relative RMS difference
# falls as the evaluation budget grows, the final image is within the
# reference's own noise of it in every 8 x 8 block (the reference's
# standard errors come from 16 independent path tracer runs), and the
# image mean agrees. Release build: numbers, not memory checks.
. "$(dirname "$0")/lib.sh"
BS="$BUILD/release/tools/gi_blockstats"
refs=""
for s in $(seq 1 16); do
    write_job "$TMP/pt$s.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "pt", "seed": $s,
 "image": {"width": 32, "height": 32}, "pt": {"spp": 256, "max_bounces": 1},
 "outputs": {"exr": "pt$s.exr"}}
JOB
    "$GI_RELEASE" render "$TMP/pt$s.json" --workers 2 --out "$TMP" --progress none >/dev/null ||
        fail "pt reference $s"
    refs="$refs $TMP/pt$s.exr"
done
# The 16 runs averaged: the reference for per-pixel errors.
prev=""
for evals in 200000 400000 800000 3200000; do
    write_job "$TMP/q$evals.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "quadrature",
 "image": {"width": 32, "height": 32}, "quadrature": {"dims": 4, "max_evals": $evals},
 "outputs": {"exr": "q$evals.exr", "report": "q$evals.report"}}
JOB
    "$GI_RELEASE" render "$TMP/q$evals.json" --workers 2 --out "$TMP" --progress none >/dev/null ||
        fail "quadrature $evals"
    r=$("$IMGTOOL" rmse "$TMP/q$evals.exr" "$TMP/pt1.exr")
    echo "budget $evals: relative RMS difference to one 256 spp path tracer run $r"
    if [ -n "$prev" ]; then
        awk -v a="$r" -v b="$prev" 'BEGIN { exit !(a <= b * 1.02) }' ||
            fail "error grew from $prev to $r with the budget"
    fi
    prev=$r
done
# At the largest budget the difference to one pt run is that run's noise:
# against a second run it is no smaller.
noise=$("$IMGTOOL" rmse "$TMP/pt2.exr" "$TMP/pt1.exr")
echo "two path tracer runs differ by $noise"
awk -v a="$prev" -v n="$noise" 'BEGIN { exit !(a < n) }' ||
    fail "quadrature ($prev) is not closer to a pt run than another pt run is ($noise)"
"$BS" 8 3 $refs -- "$TMP/q3200000.exr" || fail "a block differs by more than 3 standard errors"
# Coarse budgets are biased in places (the test can fail).
if "$BS" 8 3 $refs -- "$TMP/q200000.exr" >/dev/null; then fail "200k evaluations already converged?"; fi
echo ok
