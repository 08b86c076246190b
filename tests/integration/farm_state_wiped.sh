# A coordinator whose state directory was wiped gives job ids again; a
# worker that ran through it must not take the new job 1 for the old one:
# its pool children had loaded the old job's scene and seed. The new jobs'
# outputs must be those of `gi render` (job 1: another pt job; job 2: the
# same animation again, whose batch directory the worker removed when it
# first ended).
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
cornell_job "$TMP/a.json" 1 32 32 16
cornell_job "$TMP/b.json" 7 32 32 16
write_job "$TMP/anim.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene-mobile.json", "method": "detp", "seed": 3,
 "detp": {"photons": 40000, "batch": 20000, "subdivide": 60,
          "animation": {"object": "mobile", "frames": 3,
                        "keyframes": [{"frame": 0, "translate": [340, -338.9, -90]},
                                      {"frame": 2, "translate": [300, -338.9, -50]}]}},
 "outputs": {"bin": "v.bin"}}
JOB
render_refs b anim
OPTS="--heartbeat 0.2 --lease 2 --dead 10"
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$TMP/farmd.log" -- $OPTS
PORTS="--listen-workers $WADDR --listen-api $API"
start_worker "$TMP/worker.log" -- --connect "$WADDR" --procs 2 --cache "$TMP/cache"
"$GI" submit "$TMP/a.json" --wait --out "$TMP/a" --progress none >/dev/null 2>&1 || fail "job a"
"$GI" submit "$TMP/anim.json" --wait --out "$TMP/anim1" --progress none >/dev/null 2>&1 || fail "animation"

# The state wiped; the worker runs on and reconnects.
stop_farmd "$TMP/farmd.log"
rm -rf "$TMP/state"
# shellcheck disable=SC2086
start_farmd "$TMP/state" "$TMP/farmd.log" -- $OPTS $PORTS
id=$("$GI" submit "$TMP/b.json" 2>"$TMP/submit.log") || { cat "$TMP/submit.log"; fail "submit b"; }
[ "$id" = 1 ] || fail "the wiped coordinator gave job id $id, not 1"
"$GI" wait "$id" --out "$TMP/b" --progress none >/dev/null 2>&1 || fail "job b"
for f in "$TMP"/ref-b/*; do
    cmp "$f" "$TMP/b/$(basename "$f")" || fail "job 1 again: $(basename "$f") is not the new job's"
done
"$GI" submit "$TMP/anim.json" --wait --out "$TMP/anim2" --progress none >"$TMP/anim2.log" 2>&1 ||
    { cat "$TMP/anim2.log"; fail "the animation as job 2 again"; }
for f in "$TMP"/ref-anim/v.*.bin; do
    cmp "$f" "$TMP/anim2/$(basename "$f")" || fail "animation again: $(basename "$f") differs"
done
stop_farmd "$TMP/farmd.log"
echo "job ids given again after a wiped state run as the new jobs"
