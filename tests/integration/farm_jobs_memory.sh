# Jobs the farm keeps hold its memory until purged (a cancelled job keeps
# its text for a retry): past --max-jobs-memory a submission is refused
# (503, saying what to do) instead of the coordinator growing without
# bound, and a purge makes room again.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
make_secrets
LOG="$TMP/farmd.log"
start_farmd "$TMP/state" "$LOG" -- --max-jobs-memory 3M
scene="$SRC/scenes/cornell-box/scene.json"
h=$(b2sum -l 256 "$scene" | cut -d' ' -f1)
api "/api/v1/assets/$h" -o /dev/null -X PUT --data-binary @"$scene"
# A job of a little over 1 MiB (its description).
{
    printf '{"job": {"scene": "scene.json", "method": "pt", "image": {"width": 8, "height": 8},'
    printf ' "description": "'
    head -c 1048576 /dev/zero | tr '\0' x
    printf '"}, "assets": {"scene.json": "%s"}}' "$h"
} >"$TMP/big.json"
submit() {
    api /api/v1/jobs -o "$TMP/r" -w '%{http_code}' -X POST --data-binary @"$TMP/big.json"
}
for n in 1 2; do
    code=$(submit)
    [ "$code" = 201 ] || { cat "$TMP/r"; fail "job $n: HTTP $code"; }
    api "/api/v1/jobs/$n" -o /dev/null -X DELETE
done
code=$(submit)
[ "$code" = 503 ] && grep -q "would pass --max-jobs-memory.*gi purge" "$TMP/r" ||
    { cat "$TMP/r"; fail "a third job past --max-jobs-memory: HTTP $code"; }
api "/api/v1/jobs/1?purge=1" -o /dev/null -X DELETE
code=$(submit)
[ "$code" = 201 ] || { cat "$TMP/r"; fail "a job after a purge: HTTP $code"; }
api /api/v1/jobs/3 -o /dev/null -X DELETE
stop_farmd "$LOG"
