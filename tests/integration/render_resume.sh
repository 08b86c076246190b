# `gi render --resume`: a detp animation interrupted (SIGINT) in the middle,
# and another killed outright (SIGKILL, so only the periodic checkpoint is
# left), each resumed to frames byte-identical with an uninterrupted render.
# The stopped render keeps its photon batches under TMPDIR and the resumed
# one reads them instead of tracing them again (no frame regenerated), then
# removes them. A render that fails on a write (an output path taken by a
# directory) keeps its last checkpoint and batches and resumes once the way
# is clear. A checkpoint of an edited job is refused; a finished render
# leaves no checkpoint behind; a render that starts over in place of a
# stopped one removes the batches that one kept, and a render removes the
# batch roots of renders stopped over 3 days ago, and at once those of
# renders killed before any checkpoint. SIGHUP stops a render as SIGINT
# does. Then a pt still, interrupted and resumed the same way, and one
# whose image cannot be written: its whole result is checkpointed, a
# resume with the way still blocked fails again and keeps it, and once the
# way is clear a resume only writes the image.
. "$(dirname "$0")/lib.sh"
mkdir -p "$TMP/tmp"
export TMPDIR="$TMP/tmp"
# Batch roots of older renders: one untouched for 4 days (swept by the next
# render), a fresh one (kept: it may be resumed), an old one others may
# enter and an old plain directory (not a render's own: never touched).
for d in gi-render-old4dy gi-render-fresh0 gi-render-opened other-dir; do
    mkdir -p "$TMPDIR/$d/1-0123456789abcdef" && chmod 700 "$TMPDIR/$d"
done
chmod 755 "$TMPDIR/gi-render-opened"
for d in gi-render-old4dy gi-render-opened other-dir; do touch -d '4 days ago' "$TMPDIR/$d"; done
write_job "$TMP/job.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene-mobile.json", "method": "detp", "seed": 5,
 "image": {"width": 48, "height": 36},
 "detp": {"photons": 200000, "batch": 25000, "subdivide": 40, "tile": 16, "image_spp": 1,
          "animation": {"object": "mobile", "frames": 16,
                        "keyframes": [{"frame": 0, "translate": [340, -338.9, -90]},
                                      {"frame": 15, "translate": [248, -338.9, -0.4]}]}},
 "outputs": {"exr": "img.exr", "bin": "v.bin", "json": "report.json"}}
JOB
"$GI_RELEASE" render "$TMP/job.json" --workers 2 --out "$TMP/ref" --progress none \
    >"$TMP/ref.log" 2>&1 || { cat "$TMP/ref.log"; fail "reference render"; }
[ ! -e "$TMP/ref/.job.checkpoint" ] || fail "a finished render left its checkpoint"
[ ! -e "$TMPDIR/gi-render-old4dy" ] || fail "a batch root untouched for 4 days was not swept"
for d in gi-render-fresh0 gi-render-opened other-dir; do
    [ -d "$TMPDIR/$d/1-0123456789abcdef" ] || fail "the sweep removed $d"
    rm -rf "${TMPDIR:?}/$d"
done

same_as_ref() { # same_as_ref DIR WHAT
    n=0
    for f in "$TMP"/ref/*; do
        case $f in *.json) continue ;; esac # reports hold timings
        cmp "$f" "$1/$(basename "$f")" || fail "$2: $(basename "$f") differs"
        n=$((n + 1))
    done
    [ $n -eq 32 ] || fail "$2: $n outputs compared, expected 32"
}
# start_and_stop DIR SIGNAL: renders into DIR, and once its frame 3 is
# written, sends SIGNAL; the render must end without finishing.
start_and_stop() {
    "$GI_RELEASE" render "$TMP/job.json" --workers 2 --out "$1" --progress none \
        --checkpoint 0.1 >"$1.log" 2>&1 &
    pid=$!
    n=0
    until [ -e "$1/img.0003.exr" ]; do
        n=$((n + 1))
        [ $n -lt 600 ] || fail "frame 3 never appeared in $1"
        kill -0 $pid 2>/dev/null || { cat "$1.log"; fail "the render of $1 ended too soon"; }
        sleep 0.05
    done
    kill "-$2" $pid
    st=0
    wait $pid || st=$?
    [ $st -ne 0 ] || fail "the render of $1 finished before its $2"
    [ ! -e "$1/img.0015.exr" ] || fail "$1: the last frame was written before the $2"
    [ -s "$1/.job.checkpoint" ] || { cat "$1.log"; fail "$1: no checkpoint after $2"; }
}

# resume_kept DIR WHAT: resumes the render stopped in DIR (by WHAT), which
# must read the photon batches the stopped one kept; its log is DIR-resume.log.
resume_kept() {
    "$GI_RELEASE" render "$TMP/job.json" --workers 2 --out "$1" --progress none --resume \
        >"$1-resume.log" 2>&1 || { cat "$1-resume.log"; fail "resume after $2"; }
    grep -q "resuming from" "$1-resume.log" || fail "the resume after $2 did not say so"
    grep -q "reading the photon batches kept in" "$1-resume.log" ||
        { cat "$1-resume.log"; fail "the resume after $2 did not read the kept batches"; }
}

# batch_roots: how many render batch roots TMPDIR holds.
batch_roots() { ls "$TMPDIR" | grep -c '^gi-render-' || true; }

start_and_stop "$TMP/int" INT
grep -q "is kept in .* and its photon batches in $TMPDIR/gi-render-.*--resume. continues" \
    "$TMP/int.log" || { cat "$TMP/int.log"; fail "no resume hint naming the batches"; }
[ "$(batch_roots)" -eq 1 ] || fail "the interrupted render kept $(batch_roots) batch roots, not 1"
# The job edited since: its checkpoint is refused, and kept.
sed 's/"seed": 5/"seed": 6/' "$TMP/job.json" >"$TMP/job.edited"
cp "$TMP/job.json" "$TMP/job.orig"
cp "$TMP/job.edited" "$TMP/job.json"
st=0
"$GI_RELEASE" render "$TMP/job.json" --out "$TMP/int" --progress none --resume >"$TMP/edit.log" 2>&1 ||
    st=$?
[ $st -eq 2 ] || { cat "$TMP/edit.log"; fail "resuming an edited job: exit $st, expected 2"; }
grep -q "a checkpoint of another run" "$TMP/edit.log" || { cat "$TMP/edit.log"; fail "edited job"; }
cp "$TMP/job.orig" "$TMP/job.json"
resume_kept "$TMP/int" SIGINT
same_as_ref "$TMP/int" "resumed after SIGINT"
[ ! -e "$TMP/int/.job.checkpoint" ] || fail "a resumed render left its checkpoint"
# Every frame found its batches stored: none was traced again.
regen=$(grep -ho '"frames_regenerated":[^,}]*' "$TMP"/int/report.*.json | grep -vc ':[[:space:]]*0$' || true)
[ "$regen" -eq 0 ] || fail "$regen frames regenerated batches after the resume"
[ "$(batch_roots)" -eq 0 ] || fail "the finished render left its batch root"

start_and_stop "$TMP/kill" KILL
"$GI_RELEASE" render "$TMP/job.json" --workers 3 --out "$TMP/kill" --progress none --resume \
    >"$TMP/kill-resume.log" 2>&1 || { cat "$TMP/kill-resume.log"; fail "resume after SIGKILL"; }
same_as_ref "$TMP/kill" "resumed after SIGKILL (3 workers)"
[ "$(batch_roots)" -eq 0 ] || fail "the render resumed after SIGKILL left its batch root"

# An output that cannot be written (a directory in its way, as a full disk
# would): the render fails naming it and keeps all it rendered: frame 9's
# image (written while frame 10 ran) and frame 10, whole. A resume with the
# way still blocked fails again and keeps them; once the way is clear, a
# resume writes frame 9's image and goes on at frame 10's outputs: nothing
# of frame 9 is rendered (nor written) again.
mkdir -p "$TMP/blocked/img.0009.exr"
st=0
"$GI_RELEASE" render "$TMP/job.json" --workers 2 --out "$TMP/blocked" --progress none \
    --checkpoint 0.05 >"$TMP/blocked.log" 2>&1 || st=$?
[ $st -ne 0 ] || fail "a render whose output path is a directory succeeded"
grep -q "img.0009.exr: rename: .*(.*frame 10 of 16) is kept in .*--resume. continues" \
    "$TMP/blocked.log" || { cat "$TMP/blocked.log"; fail "no resume hint after a failed write"; }
[ "$(batch_roots)" -eq 1 ] || fail "the failed render kept $(batch_roots) batch roots, not 1"
st=0
"$GI_RELEASE" render "$TMP/job.json" --workers 2 --out "$TMP/blocked" --progress none --resume \
    >"$TMP/blocked-again.log" 2>&1 || st=$?
[ $st -ne 0 ] && grep -q "img.0009.exr: rename: .*frames rendered so far stay in .*--resume writes" \
    "$TMP/blocked-again.log" || { cat "$TMP/blocked-again.log"; fail "resumed, still blocked: exit $st"; }
[ "$(batch_roots)" -eq 1 ] || fail "the render still blocked kept $(batch_roots) batch roots, not 1"
touch -d '1 minute ago' "$TMP/blocked"/*.*
touch -d '30 seconds ago' "$TMP/before-resume"
rmdir "$TMP/blocked/img.0009.exr"
"$GI_RELEASE" render "$TMP/job.json" --workers 2 --out "$TMP/blocked" --progress none --resume \
    >"$TMP/blocked-resume.log" 2>&1 || { cat "$TMP/blocked-resume.log"; fail "resume after a failed write"; }
! grep -q "missing" "$TMP/blocked-resume.log" || { cat "$TMP/blocked-resume.log"; fail "frames missing"; }
written=$(cd "$TMP/blocked" && find . -name '*.0*' -newer "$TMP/before-resume" | sort | tr '\n' ' ')
[ "$written" = "./img.0009.exr ./img.0010.exr ./img.0011.exr ./img.0012.exr ./img.0013.exr \
./img.0014.exr ./img.0015.exr ./report.0010.json ./report.0011.json ./report.0012.json \
./report.0013.json ./report.0014.json ./report.0015.json ./v.0010.bin ./v.0011.bin ./v.0012.bin \
./v.0013.bin ./v.0014.bin ./v.0015.bin " ] || fail "the resume wrote $written"
same_as_ref "$TMP/blocked" "resumed after a failed write"
[ "$(batch_roots)" -eq 0 ] || fail "the render resumed after a failed write left its batch root"

# Starting over instead of resuming: the stopped render's batches go.
start_and_stop "$TMP/over" INT
[ "$(batch_roots)" -eq 1 ] || fail "no batch root kept for $TMP/over"
"$GI_RELEASE" render "$TMP/job.json" --workers 2 --out "$TMP/over" --progress none \
    >"$TMP/over-again.log" 2>&1 || { cat "$TMP/over-again.log"; fail "starting over"; }
grep -q "this run starts over" "$TMP/over-again.log" || fail "starting over did not warn"
same_as_ref "$TMP/over" "started over"
[ "$(batch_roots)" -eq 0 ] || fail "starting over left the stopped render's batch root"

# SIGHUP (the terminal went away) stops a render like SIGINT: resumable.
start_and_stop "$TMP/hup" HUP
[ "$(batch_roots)" -eq 1 ] || fail "no batch root kept after SIGHUP"
rm "$TMP/hup/v.0001.bin" # a frame written before the stop, deleted since: said so
resume_kept "$TMP/hup" SIGHUP
grep -q "1 output of the frames before frame [0-9]* is missing (.*/hup/v.0001.bin)" "$TMP/hup-resume.log" ||
    { cat "$TMP/hup-resume.log"; fail "a deleted frame output was not reported"; }
cp "$TMP/ref/v.0001.bin" "$TMP/hup/"
same_as_ref "$TMP/hup" "resumed after SIGHUP"

# Killed before its first checkpoint: nothing can resume its batches, so
# the next render (of anything, anywhere) removes them at once.
"$GI_RELEASE" render "$TMP/job.json" --workers 2 --out "$TMP/early" --progress none \
    --checkpoint 0 >"$TMP/early.log" 2>&1 &
pid=$!
n=0
until ls "$TMPDIR"/gi-render-*/*/b* >/dev/null 2>&1; do
    n=$((n + 1))
    [ $n -lt 600 ] || { cat "$TMP/early.log"; fail "the early render wrote no batch"; }
    sleep 0.05
done
kill -KILL $pid
wait $pid 2>/dev/null || true
[ ! -e "$TMP/early/.job.checkpoint" ] || fail "a checkpoint was written with --checkpoint 0"
[ "$(batch_roots)" -eq 1 ] || fail "the killed render left $(batch_roots) batch roots, not 1"
GI_LOG=info "$GI_RELEASE" render "$TMP/job.json" --workers 2 --out "$TMP/after" --progress none \
    >"$TMP/after.log" 2>&1 || { cat "$TMP/after.log"; fail "render after an early kill"; }
grep -q "removed 1 batch directory of earlier renders that cannot be resumed" "$TMP/after.log" ||
    { cat "$TMP/after.log"; fail "the orphaned batch root was not reported removed"; }
[ "$(batch_roots)" -eq 0 ] || fail "the batch root of a render killed before its first checkpoint stays"

# A still: pt, interrupted among its passes.
write_job "$TMP/pt.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "pt", "seed": 2,
 "image": {"width": 96, "height": 72}, "pt": {"spp": 256, "tile": 16, "pass_spp": 4},
 "outputs": {"exr": "pt.exr"}}
JOB
"$GI_RELEASE" render "$TMP/pt.json" --workers 2 --out "$TMP/pt-ref" --progress none >/dev/null 2>&1 ||
    fail "pt reference"
"$GI_RELEASE" render "$TMP/pt.json" --workers 2 --out "$TMP/pt" --progress none --checkpoint 0.1 \
    >"$TMP/pt.log" 2>&1 &
pid=$!
n=0
until [ -s "$TMP/pt/.pt.checkpoint" ]; do
    n=$((n + 1))
    [ $n -lt 600 ] || fail "no pt checkpoint"
    sleep 0.05
done
kill -INT $pid
wait $pid && fail "the pt render finished before its SIGINT"
[ ! -e "$TMP/pt/pt.exr" ] || fail "an interrupted still wrote its image"
[ "$(batch_roots)" -eq 0 ] || fail "a stopped pt render (no batches) kept a batch root"
grep -q "photon batches" "$TMP/pt.log" && fail "a stopped pt render spoke of photon batches"
"$GI_RELEASE" render "$TMP/pt.json" --workers 2 --out "$TMP/pt" --progress none --resume \
    >"$TMP/pt-resume.log" 2>&1 || { cat "$TMP/pt-resume.log"; fail "pt resume"; }
cmp "$TMP/pt-ref/pt.exr" "$TMP/pt/pt.exr" || fail "pt: the resumed image differs"
mkdir -p "$TMP/pt-blocked/pt.exr"
blocked() { # blocked RUN PATTERN [--resume]: the render fails on its image, saying PATTERN
    st=0
    "$GI_RELEASE" render "$TMP/pt.json" --workers 2 --out "$TMP/pt-blocked" --progress none \
        ${3:-} >"$TMP/pt-$1.log" 2>&1 || st=$?
    [ $st -eq 1 ] && grep -q "pt.exr: rename: .*$2" "$TMP/pt-$1.log" ||
        { cat "$TMP/pt-$1.log"; fail "pt blocked ($1): exit $st"; }
}
blocked first "work done (100%) is kept in .*--resume. continues"
blocked again "the whole result stays in .*--resume writes the outputs" --resume
rmdir "$TMP/pt-blocked/pt.exr"
"$GI_RELEASE" render "$TMP/pt.json" --workers 2 --out "$TMP/pt-blocked" --progress none --resume \
    >"$TMP/pt-unblocked.log" 2>&1 || { cat "$TMP/pt-unblocked.log"; fail "pt resume, unblocked"; }
grep -q "resuming from .* (100% done)" "$TMP/pt-unblocked.log" || fail "pt rendered again"
cmp "$TMP/pt-ref/pt.exr" "$TMP/pt-blocked/pt.exr" || fail "pt: the image written on resume differs"
echo "detp animation resumed after SIGINT and SIGKILL, pt after SIGINT and a failed write: same"

