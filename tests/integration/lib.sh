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
# render JOB OUT WORKERS [PROGRESS]: `gi render` (ASan build) into OUT, its
# output in OUT.log, shown if it fails.
render() {
    "$GI" render "$1" --workers "$3" --out "$2" --progress "${4:-none}" >"$2.log" 2>&1 ||
        { cat "$2.log"; fail "render $2"; }
}
# The camera path tests' keys over the Cornell box: frame 0 the scene's
# camera, frame 2 another view (a path of 4 frames: frame 3 holds it).
CAM_KEY0='"position": [278, 273, -800], "look_at": [278, 273, 0], "up": [0, 1, 0], "fov_y": 39.3'
CAM_KEY2='"position": [100, 300, -600], "look_at": [278, 200, 300], "up": [0, 1, 0], "fov_y": 50'
# A camera path's frames in DIR (NAME.0000.exr ...; those keys): frame 2 is
# STILL (the still seen from key 2's camera) bit for bit, the held frame 3
# is frame 2, and frame 1, between the keys, is neither.
#   camera_path_frames DIR NAME STILL
camera_path_frames() {
    cmp "$3" "$1/$2.0002.exr" || fail "$1: frame 2 is not the still seen from its key's camera"
    cmp "$1/$2.0002.exr" "$1/$2.0003.exr" || fail "$1: the held frame 3 differs from frame 2"
    for f in 0000 0002; do
        if cmp -s "$1/$2.0001.exr" "$1/$2.$f.exr"; then fail "$1: frame 1 is frame $f"; fi
    done
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
