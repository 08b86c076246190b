# Sourced by integration tests. The runner sets GI (ASan build of gi),
# GI_RELEASE (optimized build), IMGTOOL, SRC (source tree), TMP (scratch).
set -eu
# FAIL_LOGS: logs whose last lines a failure shows (what a CI run keeps).
fail() {
    for l in ${FAIL_LOGS:-}; do
        [ -f "$l" ] && { echo "--- last lines of $l"; tail -n 40 "$l"; }
    done
    echo "FAIL: $*"
    exit 1
}
skip() {
    echo "skipped: $*"
    exit 77
}
# Writes a job file: write_job PATH <<EOF ... EOF
write_job() {
    cat >"$1"
}
# Renders JOB into OUT with 2 workers (release build) and, DELAY seconds
# after the first pool child appears, kills it with SIGKILL from outside;
# fails unless the render still succeeds and reports the crash.
#   render_killing_a_child JOB OUT DELAY
render_killing_a_child() {
    "$GI_RELEASE" render "$1" --workers 2 --out "$2" --progress none >"$2.log" 2>&1 &
    parent=$!
    killed=0
    for i in $(seq 1 100); do
        kid=$(pgrep -P $parent | head -n 1 || true)
        if [ -n "$kid" ]; then
            sleep "$3"
            kill -9 "$kid" 2>/dev/null && killed=1
            break
        fi
        sleep 0.05
    done
    wait $parent || { cat "$2.log"; fail "render after kill -9 of a child"; }
    [ $killed -eq 1 ] || fail "never found a child to kill"
    grep -q "worker crash" "$2.log" || { cat "$2.log"; fail "the kill was not noticed"; }
}
