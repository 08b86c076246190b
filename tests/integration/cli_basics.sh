# The command line: validate (a job, a scene alone, an emissions file), methods, --help, JSON progress, the summary, a bare
# OBJ (+ MTL with Kd/Ke) as a whole scene with the default camera, the default
# pool size under a narrowed CPU set, and an interrupted render leaving no output.
. "$(dirname "$0")/lib.sh"
cp "$SRC/tests/data/meshes/two_materials.obj" "$SRC/tests/data/meshes/two_materials.mtl" "$TMP/"
write_job "$TMP/obj.json" <<JOB
{"scene": "two_materials.obj", "method": "pt", "image": {"width": 32, "height": 24},
 "pt": {"spp": 8}, "outputs": {"exr": "obj.exr", "png": "obj.png"}}
JOB
"$GI" validate "$TMP/obj.json" >"$TMP/validate.txt" || fail "validate"
grep -q "ok (pt, scene two_materials.obj: 1 objects, 3 triangles, 1 emissive)" "$TMP/validate.txt" ||
    { cat "$TMP/validate.txt"; fail "validate output"; }
# A detp bake of big faces with "auto" discs is warned about by validate
# already, not only once the render runs.
write_job "$TMP/coarse.json" <<JOB
{"scene": "two_materials.obj", "method": "detp", "detp": {"photons": 1000}}
JOB
"$GI" validate "$TMP/coarse.json" >/dev/null 2>"$TMP/coarse.err" || fail "validate a coarse bake"
grep -q "warning: coarse: detp: the discs' radius is .*: a coarse bake; set detp.subdivide" \
    "$TMP/coarse.err" || { cat "$TMP/coarse.err"; fail "validate does not warn of a coarse bake"; }
# A scene alone: a bare mesh, a scene JSON; a bad one is refused (exit 2).
"$GI" validate "$TMP/two_materials.obj" | grep -q "two_materials.obj: ok (scene: 1 objects, 3 triangles, 1 emissive)" ||
    fail "validate a bare mesh"
"$GI" validate "$SRC/scenes/cornell-box/scene.json" | grep -q "ok (scene: 8 objects, 32 triangles, 2 emissive)" ||
    fail "validate a scene"
# Told a scene from a job when its keys lie past gi validate's first read
# (64 KiB), "objects" across the boundary: the file is read in pieces.
at=$(grep -bo '"objects"' "$SRC/scenes/cornell-box/scene.json" | head -n 1 | cut -d: -f1)
{ printf '{'; head -c $((65533 - at)) /dev/zero | tr '\0' ' '; tail -c +2 "$SRC/scenes/cornell-box/scene.json"; } \
    >"$TMP/padded-scene.json"
"$GI" validate "$TMP/padded-scene.json" | grep -q "ok (scene: 8 objects, 32 triangles, 2 emissive)" ||
    fail "validate a scene whose keys are past 64 KiB"
printf '{"objects": [{"name": "a", "material": "x", "quad": {"size": [1, 1]}}]}' >"$TMP/bad-scene.json"
set +e
"$GI" validate "$TMP/bad-scene.json" 2>"$TMP/bad-scene.log"
rc=$?
set -e
[ $rc -eq 2 ] && grep -q 'material "x" is not defined' "$TMP/bad-scene.log" ||
    { cat "$TMP/bad-scene.log"; fail "a bad scene: exit $rc"; }
# An emissions file (gi relight's): alone, its own fields (names unchecked,
# it says so); with its radiosity job, its names against the job's scene;
# bad ones refused naming file and field (exit 2).
EM="$SRC/scenes/cornell-box/emissions.json"
RJOB="$SRC/scenes/cornell-box/radiosity.json"
"$GI" validate "$EM" >"$TMP/em.out" || fail "validate an emissions file alone"
grep -q "emissions.json: ok (3 emission sets: scene, blue, lamp; its material and object names \
are not checked without the job: gi validate JOB.json " "$TMP/em.out" ||
    { cat "$TMP/em.out"; fail "validate an emissions file alone: what it says"; }
for args in "$RJOB $EM" "$EM $RJOB"; do
    # shellcheck disable=SC2086
    "$GI" validate $args >"$TMP/em.out" || fail "validate $args"
    grep -q "emissions.json: ok (3 emission sets: scene, blue, lamp; names found in .*radiosity\.json's \
scene scene.json)" "$TMP/em.out" || { cat "$TMP/em.out"; fail "validate $args: what it says"; }
done
em_refused() { # em_refused WHAT MESSAGE FILE...
    what=$1 msg=$2
    shift 2
    set +e
    "$GI" validate "$@" >"$TMP/em.out" 2>"$TMP/em.log"
    rc=$?
    set -e
    [ $rc -eq 2 ] && [ ! -s "$TMP/em.out" ] && grep -q "$msg" "$TMP/em.log" ||
        { cat "$TMP/em.out" "$TMP/em.log"; fail "validate $what: exit $rc"; }
}
sed 's/"tall_block"/"tall_blok"/' "$EM" >"$TMP/em-obj.json"
em_refused "an unknown object" "em-obj.json: emissions\[2\].objects: no object \"tall_blok\" in \
the scene (its objects: .*tall_block" "$RJOB" "$TMP/em-obj.json"
sed 's/"light": \[2/"lite": [2/' "$EM" >"$TMP/em-mat.json"
em_refused "an unknown material" "em-mat.json: emissions\[1\].materials: no material \"lite\"" \
    "$RJOB" "$TMP/em-mat.json"
echo '{"emissions": [{"name": "a", "scale": -1}]}' >"$TMP/em-scale.json"
em_refused "a bad scale" "em-scale.json: emissions\[0\].scale: -1 is out of range" \
    "$TMP/em-scale.json"
em_refused "with a pt job" "pt.json: an emissions file is for a radiosity job (gi relight), not pt" \
    "$SRC/scenes/cornell-box/pt.json" "$EM"
em_refused "twice" "two files must be a radiosity job and an emissions file" "$EM" "$EM"
# A scene or an emissions file given to gi render: what it is, and what a job is.
for f in scene.json emissions.json; do
    set +e
    "$GI" render "$SRC/scenes/cornell-box/$f" --out "$TMP/not-a-job" 2>"$TMP/not-job.log"
    rc=$?
    set -e
    [ $rc -eq 2 ] && grep -q "$f: method: missing (required): this is an* [a-z]*.*, not a job; \
a job names its scene (\"scene\") and a method" "$TMP/not-job.log" ||
        { cat "$TMP/not-job.log"; fail "gi render $f: exit $rc"; }
done
# gi submit checks the job file before it looks for a token or a farm: a
# bad job is told as gi validate tells it, not "no API token"; a good one
# without a token is then told about the token.
for tok in none given; do
    rc=0
    if [ $tok = none ]; then
        env -u GI_FARM_TOKEN -u GI_FARM_TOKEN_FILE "$GI" submit "$SRC/tests/data/bad/bad-camera.json" \
            --retry 0 >"$TMP/submit.out" 2>"$TMP/submit.err" || rc=$?
    else # and with a token, before the farm (none here) is asked
        GI_FARM_TOKEN=abcdefghijklmnopqrstuvwxyz012345 GI_FARM=http://127.0.0.1:9 \
            "$GI" submit "$SRC/tests/data/bad/bad-camera.json" --retry 0 >"$TMP/submit.out" \
            2>"$TMP/submit.err" || rc=$?
    fi
    [ $rc -eq 2 ] && [ "$(cat "$TMP/submit.err")" = "gi: $SRC/tests/data/bad/bad-camera.json: \
camera.up: is zero or parallel to the view direction" ] && [ ! -s "$TMP/submit.out" ] ||
        { cat "$TMP/submit.err"; fail "gi submit of a bad job ($tok token): exit $rc"; }
done
rc=0
env -u GI_FARM_TOKEN -u GI_FARM_TOKEN_FILE "$GI" submit "$TMP/obj.json" --retry 0 \
    2>"$TMP/submit.err" || rc=$?
[ $rc -eq 2 ] && grep -q "^gi: no API token" "$TMP/submit.err" ||
    { cat "$TMP/submit.err"; fail "gi submit of a good job with no token: exit $rc"; }
# gi validate tells a job from a scene or an emissions file by its top-level
# keys, not by parsing it whole: a job over its 16 MiB limit is refused by
# its size before anything parses it (it took 765 MB and 3 s to parse that
# one first); a scene JSON past 16 MiB is a scene all the same.
python3 -c 'import sys; sys.stdout.write("{\"method\": \"pt\", \"pad\": [" + "1," * 9000000 + "1]}")' \
    >"$TMP/huge.json"
size=$(wc -c <"$TMP/huge.json")
python3 - "$GI_RELEASE" "$TMP/huge.json" >"$TMP/huge.out" 2>"$TMP/huge.err" <<'PY' ||
import resource, subprocess, sys
rc = subprocess.call([sys.argv[1], "validate", sys.argv[2]])
print("rc", rc, "maxrss_kb", resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)
PY
    fail "measuring gi validate of a huge job"
[ "$(cat "$TMP/huge.err")" = "gi: $TMP/huge.json: file is $size bytes, over the limit of 16777216" ] &&
    grep -q "^rc 2 " "$TMP/huge.out" ||
    { cat "$TMP/huge.out" "$TMP/huge.err"; fail "gi validate of a job over 16 MiB"; }
[ "$(awk '{print $4}' "$TMP/huge.out")" -lt 150000 ] ||
    { cat "$TMP/huge.out"; fail "gi validate parsed a job over its limit before refusing it"; }
python3 - "$SRC/scenes/cornell-box/scene.json" "$TMP/huge-scene.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
s["description"] = "x" * (17 << 20)
json.dump(s, open(sys.argv[2], "w"))
PY
"$GI" validate "$TMP/huge-scene.json" | grep -q "huge-scene.json: ok (scene: 8 objects" ||
    fail "gi validate of a scene JSON past 16 MiB"
rm -f "$TMP/huge.json" "$TMP/huge-scene.json"
"$GI" methods | grep -q "^pt " || fail "methods does not list pt"
"$GI" --version | grep -q "^gi [0-9]" || fail "--version"
for cmd in "" render submit relight; do
    # shellcheck disable=SC2086
    "$GI" $cmd --help | grep -q "^usage: gi render" || fail "gi $cmd --help"
done

"$GI" render "$TMP/obj.json" --workers 2 --out "$TMP/out" --progress json >"$TMP/summary.txt" 2>"$TMP/progress.txt" ||
    { cat "$TMP/progress.txt"; fail "render"; }
# Every progress line is a JSON object with the fields a program needs; every
# output written has its event, and the last line says how the render ended.
while read -r line; do
    case "$line" in
    '{"event":"progress","job":"obj",'*'"fraction":'*'"eta_s":'*) ;;
    '{"event":"output","job":"obj","kind":"'*'","path":"'*) ;;
    '{"event":"end","job":"obj","state":"done","elapsed_s":'*'}') ;;
    *) fail "not a JSON progress line: $line" ;;
    esac
done <"$TMP/progress.txt"
[ "$(grep -c '"event":"output"' "$TMP/progress.txt")" -eq 2 ] || fail "not one output event per file"
tail -n 1 "$TMP/progress.txt" | grep -q '"event":"end"' || fail "the last JSON line is not the end"
grep -q '"fraction":1.000000' "$TMP/progress.txt" || fail "no final progress line"
grep -q "^obj: pt done in" "$TMP/summary.txt" || fail "no summary"
grep -q "samples/s" "$TMP/summary.txt" || fail "summary has no rate"
grep -q "exr  $TMP/out/obj.exr" "$TMP/summary.txt" || fail "summary does not list the EXR"
# Progress lines: no rate before any work is seen ("?", not a 0 that reads as a stall).
"$GI" render "$TMP/obj.json" --out "$TMP/out-lines" --progress lines 2>"$TMP/lines.txt" \
    >/dev/null || fail "render --progress lines"
head -n 1 "$TMP/lines.txt" | grep -q "^obj: 0.0% done, ETA ?, ? samples/s$" &&
    ! grep -q " 0 samples/s" "$TMP/lines.txt" && grep -q "^obj: 100.0% done, .* [0-9.]* [kM]*samples/s$" \
    "$TMP/lines.txt" || { cat "$TMP/lines.txt"; fail "progress lines' rate"; }
# The default camera sees the lit floor (Kd 0.7 0.6 0.5 under Ke 10 9 8).
"$IMGTOOL" stats "$TMP/out/obj.exr" >"$TMP/stats.txt"
awk '/^mean/ { exit !($2 > 0.01 && $2 > $3 && $3 > $4) }' "$TMP/stats.txt" ||
    { cat "$TMP/stats.txt"; fail "the OBJ scene renders dark or with the wrong colours"; }
ls "$TMP/out" | grep -q tmp && fail "temporary files left in the output directory"

# With no --workers, the pool follows the CPUs this process may use (here its
# affinity mask, as under taskset or a Slurm step), not the machine's.
if command -v taskset >/dev/null && [ "$(nproc --all)" -gt 1 ]; then
    taskset -c 0 "$GI" render "$TMP/obj.json" --out "$TMP/one" --progress none >"$TMP/one.txt" ||
        fail "render under taskset"
    grep -q "^obj: pt done in .* with 1 worker$" "$TMP/one.txt" ||
        { cat "$TMP/one.txt"; fail "a render limited to one CPU did not use one worker"; }
fi

# Rendered beside its job file (--out .), a job's default outputs leave it be
# (the report is NAME-report.json, not NAME.json); an output named as the
# job file or its scene is refused before anything runs.
mkdir -p "$TMP/here"
cp "$TMP/two_materials.obj" "$TMP/two_materials.mtl" "$TMP/here/"
printf '{"scene": "two_materials.obj", "method": "quadrature", "image": {"width": 8, "height": 8},
 "quadrature": {"max_evals": 20000}}' >"$TMP/here/q.json"
cp "$TMP/here/q.json" "$TMP/q.orig"
(cd "$TMP/here" && "$GI" render q.json --out . --progress none >/dev/null) || fail "render into the job's directory"
cmp -s "$TMP/here/q.json" "$TMP/q.orig" || fail "the render replaced its own job file"
grep -q '"evaluations"' "$TMP/here/q-report.json" || fail "no report named q-report.json"
printf '{"scene": "two_materials.obj", "method": "pt", "image": {"width": 8, "height": 8},
 "outputs": {"exr": "%s", "png": "new.png"}}' clash.json >"$TMP/here/clash.json"
cp "$TMP/here/clash.json" "$TMP/clash.orig"
for out in clash.json two_materials.obj; do
    sed "s/\"exr\": \"[^\"]*\"/\"exr\": \"$out\"/" "$TMP/clash.orig" >"$TMP/here/clash.json"
    cp "$TMP/here/clash.json" "$TMP/clash.now"
    set +e
    (cd "$TMP/here" && "$GI" render clash.json --out . --progress none >/dev/null 2>"$TMP/clash.err")
    rc=$?
    set -e
    [ $rc -eq 2 ] && grep -q "outputs.exr: $out would replace one of the job's own files" "$TMP/clash.err" ||
        { cat "$TMP/clash.err"; fail "an output named $out: exit $rc"; }
    [ ! -e "$TMP/here/new.png" ] || fail "a refused job wrote an output"
    cmp -s "$TMP/here/clash.json" "$TMP/clash.now" || fail "the job file changed"
done
cmp -s "$TMP/here/two_materials.obj" "$TMP/two_materials.obj" || fail "the scene's mesh changed"

# An --out that cannot take the outputs is refused before anything runs.
: >"$TMP/afile"
for case in "$TMP/afile|not a directory" "|an empty directory name"; do
    set +e
    "$GI" render "$TMP/obj.json" --out "${case%%|*}" --progress none >/dev/null 2>"$TMP/out.err"
    rc=$?
    set -e
    [ $rc -eq 2 ] && grep -q "^gi: --out: .*${case#*|}" "$TMP/out.err" ||
        { cat "$TMP/out.err"; fail "--out '${case%%|*}' exited $rc"; }
done
# Option values that are no number in range (an empty one is not 0, blanks
# and signs are not digits) are refused, naming the option, before anything runs.
for case in "render|--checkpoint|" "render|--checkpoint|nan" "render|--workers|" \
    "render|--workers| 2" "render|--workers|+2" "render|--workers|1025" \
    "relight|--workers| 2" "relight|--threads|0"; do
    cmd=${case%%|*} rest=${case#*|}
    opt=${rest%%|*} val=${rest#*|}
    set +e
    em="$TMP/em.json"
    [ "$cmd" = relight ] || em=--resume
    "$GI" "$cmd" "$TMP/obj.json" "$em" "$opt" "$val" --out "$TMP/badopt" --progress none \
        >/dev/null 2>"$TMP/opt.err"
    rc=$?
    set -e
    [ $rc -eq 2 ] && grep -q "^gi $cmd: $opt must be .*, got \"$val\"" "$TMP/opt.err" ||
        { cat "$TMP/opt.err"; fail "gi $cmd $opt '$val' exited $rc"; }
    [ ! -e "$TMP/badopt" ] || fail "gi $cmd $opt '$val' wrote something"
done

# SIGINT mid-render: exit 130, no output.
write_job "$TMP/long.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "pt", "image": {"width": 128, "height": 128},
 "pt": {"spp": 4096}, "outputs": {"exr": "long.exr"}}
JOB
"$GI_RELEASE" render "$TMP/long.json" --workers 2 --out "$TMP/int" --progress none >/dev/null 2>&1 &
pid=$!
sleep 1
kill -INT $pid
set +e
wait $pid
rc=$?
set -e
[ $rc -eq 130 ] || fail "interrupted render exited $rc, expected 130"
[ ! -e "$TMP/int/long.exr" ] || fail "interrupted render wrote an output"
pgrep -f "$TMP/long.json" >/dev/null && fail "pool children outlived the interrupted render"
echo ok
