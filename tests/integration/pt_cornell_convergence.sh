# The Cornell box at 256x256 with the path tracer: the converged mean
# radiance agrees within 2% with independent estimators (BSDF sampling only,
# next-event estimation only), and the error shrinks like 1/sqrt(samples):
# the RMS difference of two independent renders drops by ~2 at 4x samples.
. "$(dirname "$0")/lib.sh"
job() { # name seed spp strategy
    cat >"$TMP/$1.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "pt", "seed": $2,
 "image": {"width": 256, "height": 256}, "pt": {"spp": $3, "strategy": "$4"},
 "outputs": {"exr": "$1.exr"}}
JOB
    "$GI_RELEASE" render "$TMP/$1.json" --workers 2 --out "$TMP" --progress none >/dev/null ||
        fail "render $1"
}
job mis_a 1 64 mis
job mis_b 2 64 mis
job mis_c 3 256 mis
job mis_d 4 256 mis
job bsdf 5 256 bsdf
job light 6 128 light
"$IMGTOOL" stats "$TMP/mis_c.exr"
"$IMGTOOL" compare-mean "$TMP/bsdf.exr" "$TMP/mis_c.exr" 0.02 || fail "BSDF-only mean differs"
"$IMGTOOL" compare-mean "$TMP/light.exr" "$TMP/mis_c.exr" 0.02 || fail "NEE-only mean differs"
"$IMGTOOL" compare-mean "$TMP/mis_a.exr" "$TMP/mis_d.exr" 0.02 || fail "64 vs 256 spp means differ"
r64=$("$IMGTOOL" rmse "$TMP/mis_a.exr" "$TMP/mis_b.exr")
r256=$("$IMGTOOL" rmse "$TMP/mis_c.exr" "$TMP/mis_d.exr")
echo "relative RMS difference: 64 spp $r64, 256 spp $r256"
awk -v a="$r64" -v b="$r256" 'BEGIN { r = a / b; print "ratio", r; exit !(r > 1.7 && r < 2.3) }' ||
    fail "error does not shrink like 1/sqrt(samples)"
echo ok
