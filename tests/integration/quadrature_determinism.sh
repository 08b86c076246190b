# The quadrature renderer's output bits depend only on the job: 1, 2 and 3
# pool workers give byte-identical images, so do children killed mid-task
# (in the first and in later rounds), and so do the three heap kinds (their
# order is total). Pure quadrature has no noise: the seed changes nothing;
# the hybrid's Monte Carlo phase does depend on it.
. "$(dirname "$0")/lib.sh"
job() { # file rule heap hybrid seed
    write_job "$1" <<JOB
{
  "scene": "$SRC/scenes/cornell-box/scene.json",
  "method": "quadrature",
  "seed": $5,
  "image": {"width": 40, "height": 32},
  "quadrature": {"dims": 4, "rule": "$2", "heap": "$3", "max_evals": 120000, "initial": [4, 4],
                 "round_tasks": 5, "task_regions": 3, "task_splits": 12,
                 "threshold": 1e-7 $( [ "$4" = 1 ] && echo ', "hybrid": true, "mc_spp": 2') },
  "outputs": {"exr": "img.exr", "report": "report.json"}
}
JOB
}
render() { # job outdir workers
    "$GI" render "$1" --workers "$3" --out "$2" --progress none >"$2.log" 2>&1 ||
        { cat "$2.log"; fail "render $1 with $3 workers"; }
}
for rule in boole genz-malik; do
    job "$TMP/$rule.json" $rule bucketed 0 7
    for w in 1 2 3; do render "$TMP/$rule.json" "$TMP/$rule-w$w" $w; done
    cmp "$TMP/$rule-w1/img.exr" "$TMP/$rule-w2/img.exr" || fail "$rule: 1 vs 2 workers differ"
    cmp "$TMP/$rule-w1/img.exr" "$TMP/$rule-w3/img.exr" || fail "$rule: 1 vs 3 workers differ"
    grep -Eq '"rounds":[[:space:]]+([3-9]|[1-9][0-9]+),' "$TMP/$rule-w1/report.json" ||
        { cat "$TMP/$rule-w1/report.json"; fail "$rule: too few rounds to test the farm split"; }
    # Tasks 2 (round 0) and 9, 14 (later rounds) die on their first attempt.
    GI_FAULT_CRASH_TASK="2,9,14" "$GI" render "$TMP/$rule.json" --workers 2 --out "$TMP/$rule-crash" \
        --progress none >"$TMP/$rule-crash.log" 2>&1 || { cat "$TMP/$rule-crash.log"; fail "crashes"; }
    grep -q "3 retried (3 worker crashes)" "$TMP/$rule-crash.log" ||
        { cat "$TMP/$rule-crash.log"; fail "$rule: crashes not reported"; }
    cmp "$TMP/$rule-w1/img.exr" "$TMP/$rule-crash/img.exr" || fail "$rule: differs after crashes"
done
for heap in binary pairing; do
    job "$TMP/$heap.json" boole $heap 0 7
    render "$TMP/$heap.json" "$TMP/$heap" 2
    cmp "$TMP/boole-w1/img.exr" "$TMP/$heap/img.exr" || fail "$heap heap differs from bucketed"
done
job "$TMP/seed.json" boole bucketed 0 8
render "$TMP/seed.json" "$TMP/seed" 2
cmp "$TMP/boole-w1/img.exr" "$TMP/seed/img.exr" || fail "pure quadrature depends on the seed"

# Hybrid: the same bits for any worker count and after crashes, and a
# different seed gives a different image.
job "$TMP/hybrid.json" genz-malik bucketed 1 7
render "$TMP/hybrid.json" "$TMP/hybrid-w1" 1
render "$TMP/hybrid.json" "$TMP/hybrid-w3" 3
cmp "$TMP/hybrid-w1/img.exr" "$TMP/hybrid-w3/img.exr" || fail "hybrid: 1 vs 3 workers differ"
grep -q '"mc_samples":	[1-9]' "$TMP/hybrid-w1/report.json" || fail "hybrid took no samples"
GI_FAULT_CRASH_TASK="1,12" "$GI" render "$TMP/hybrid.json" --workers 2 --out "$TMP/hybrid-crash" \
    --progress none >/dev/null 2>&1 || fail "hybrid with crashes"
cmp "$TMP/hybrid-w1/img.exr" "$TMP/hybrid-crash/img.exr" || fail "hybrid differs after crashes"
job "$TMP/hybrid8.json" genz-malik bucketed 1 8
render "$TMP/hybrid8.json" "$TMP/hybrid8" 2
if cmp -s "$TMP/hybrid-w1/img.exr" "$TMP/hybrid8/img.exr"; then fail "hybrid ignores the seed"; fi
echo ok
