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
# An animation stopped (SIGINT) once its frame 1 is written, then resumed,
# gives the same frames as a render not stopped: JOB (release build, 2
# workers, a checkpoint every 0.1 s) into OUT, its reference into OUT-ref;
# FRAMES are the frames' numbers (0000 ...), NAME the image's (img: img.0003.exr).
#   stop_and_resume_animation JOB OUT NAME FRAMES...
stop_and_resume_animation() {
    job=$1 out=$2 name=$3
    shift 3
    last=$(echo "$@" | awk '{print $NF}')
    "$GI_RELEASE" render "$job" --workers 2 --out "$out-ref" --progress none >/dev/null 2>&1 ||
        fail "$job: the reference"
    "$GI_RELEASE" render "$job" --workers 2 --out "$out" --progress none --checkpoint 0.1 \
        >"$out.log" 2>&1 &
    pid=$!
    n=0
    until [ -e "$out/$name.0001.exr" ]; do
        n=$((n + 1))
        [ $n -lt 1200 ] || { cat "$out.log"; fail "$job: frame 1 never written"; }
        sleep 0.02
    done
    kill -INT $pid
    if wait $pid; then fail "$job: the render finished before its SIGINT"; fi
    [ ! -e "$out/$name.$last.exr" ] || fail "$job: a stopped render wrote its last frame"
    "$GI_RELEASE" render "$job" --workers 2 --out "$out" --progress none --resume \
        >"$out-resume.log" 2>&1 || { cat "$out-resume.log"; fail "$job: resume"; }
    grep -q "resuming from .*frame [1-9][0-9]* of $#" "$out-resume.log" ||
        { cat "$out-resume.log"; fail "$job: did not resume past frame 0"; }
    for f in "$@"; do
        cmp "$out-ref/$name.$f.exr" "$out/$name.$f.exr" || fail "$job: resumed, $name.$f.exr differs"
    done
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
