# Malformed jobs and scenes (tests/data/bad/EXPECT): each gets a clear
# one-line error naming the file and the problem, exit status 2, and no
# output is written.
. "$(dirname "$0")/lib.sh"
DATA="$SRC/tests/data/bad"
n=0
while IFS='|' read -r job expect; do
    case "$job" in '#'* | '') continue ;; esac
    n=$((n + 1))
    out="$TMP/out-$n"
    set +e
    "$GI" render "$DATA/$job" --out "$out" --progress none >"$TMP/stdout" 2>"$TMP/stderr"
    rc=$?
    set -e
    msg=$(cat "$TMP/stderr")
    [ $rc -eq 2 ] || fail "$job: exit status $rc, expected 2 ($msg)"
    [ "$(wc -l <"$TMP/stderr")" -eq 1 ] || fail "$job: error is not one line: $msg"
    case "$msg" in
    "gi: "*) ;;
    *) fail "$job: error does not start with 'gi: ': $msg" ;;
    esac
    echo "$msg" | grep -qF -- "$expect" || fail "$job: \"$msg\" does not say \"$expect\""
    echo "$msg" | grep -qF -- "$(basename "$job" .json)" || echo "$msg" | grep -qF "scenes/" ||
        fail "$job: the message names no file: $msg"
    [ ! -e "$out" ] || [ -z "$(ls -A "$out")" ] || fail "$job: output written"
    [ ! -s "$TMP/stdout" ] || fail "$job: printed a summary"
    echo "ok  $job: $msg"
done <"$DATA/EXPECT"
[ $n -ge 20 ] || fail "only $n cases"

# Command-line mistakes are exit 2 as well, before anything is sent (the
# farm commands' would otherwise fail to reach this farm: exit 1).
cat >"$TMP/ok.json" <<JOB
{"scene": "$SRC/scenes/cornell-box/scene.json", "method": "pt", "pt": {"spp": 1}}
JOB
export GI_FARM=http://127.0.0.1:9 GI_FARM_TOKEN=not-needed-by-these-commands
for args in "render" "render a.json b.json" "render x.json --workers 0" "render x.json --workers abc" \
    "render x.json --progress loud" "render x.json --frobnicate" "paint x.json" \
    "submit $TMP/ok.json --wait --progress loud" "submit $TMP/ok.json --out d" "retry 1 --progress json" \
    "cancel 1 --priority 5" "purge 1 --out d" "jobs --out d" "fetch 1 --json" "status 1 --wait"; do
    set +e
    # shellcheck disable=SC2086
    "$GI" $args >/dev/null 2>"$TMP/stderr"
    rc=$?
    set -e
    [ $rc -eq 2 ] || fail "gi $args: exit status $rc, expected 2"
    # An unknown option points at where the known ones are.
    case "$args" in
    *--frobnicate) grep -q "unknown option --frobnicate (gi --help lists them)" "$TMP/stderr" ||
        fail "gi $args: $(cat "$TMP/stderr")" ;;
    esac
done
echo "$n malformed inputs refused"
