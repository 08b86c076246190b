#!/bin/sh
# Runs the whole test suite: unit tests (ASan/UBSan build, one process per
# test), integration tests (tests/integration/*.sh), and short fuzzing runs.
# Ends with the line "N passed, N failed" (skips are counted apart).
#
#   tests/run.sh BUILD_DIR [PATTERN]     PATTERN filters test names (grep -E)
set -u
BUILD=${1:-build}
PATTERN=${2:-.}
SRC=$(cd "$(dirname "$0")/.." && pwd)
BUILD=$(cd "$BUILD" && pwd)
JOBS=${JOBS:-$(nproc 2>/dev/null || echo 2)}
OUT=$(mktemp -d "${TMPDIR:-/tmp}/gi-tests.XXXXXX")
trap 'rm -rf "$OUT"' EXIT

export GI_SRCDIR="$SRC"
export GI_TEST_TMP="$OUT"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
export LSAN_OPTIONS="suppressions=$SRC/tests/lsan.supp:${LSAN_OPTIONS:-}"

elapsed() { awk -v a="$1" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1fs", b - a }'; }

results="$OUT/results"
: >"$results"

# One line per test in $results: "PASS name seconds" / "FAIL name" / "SKIP name reason".
run_unit() {
    name=$1
    log="$OUT/unit-$name.log"
    start=$(date +%s.%N)
    if "$BUILD/asan/gi-tests" "$name" >"$log" 2>&1; then
        echo "PASS unit/$name $(elapsed "$start")" >>"$results"
    else
        echo "FAIL unit/$name" >>"$results"
        sed 's/^/    /' "$log" >"$OUT/fail-unit-$name"
    fi
}

run_integration() {
    script=$1
    name=$(basename "$script" .sh)
    log="$OUT/int-$name.log"
    dir="$OUT/int-$name"
    mkdir -p "$dir"
    start=$(date +%s.%N)
    GI="$BUILD/asan/gi" GI_RELEASE="$BUILD/release/gi" IMGTOOL="$BUILD/release/tools/gi_imgtool" \
        SRC="$SRC" BUILD="$BUILD" TMP="$dir" sh "$script" >"$log" 2>&1
    rc=$?
    secs=$(elapsed "$start")
    if [ $rc -eq 0 ]; then
        echo "PASS integration/$name $secs" >>"$results"
    elif [ $rc -eq 77 ]; then
        echo "SKIP integration/$name $(tail -n 1 "$log")" >>"$results"
    else
        echo "FAIL integration/$name" >>"$results"
        sed 's/^/    /' "$log" | tail -n 40 >"$OUT/fail-int-$name"
    fi
}

run_fuzz() {
    bin=$1
    name=$(basename "$bin")
    corpus="$SRC/tests/fuzz/corpus/${name#fuzz_}"
    work="$OUT/fuzz-$name"
    mkdir -p "$work"
    log="$OUT/$name.log"
    # A short run on a copy of the committed corpus: finds regressions, does
    # not grow the tree. `make fuzz` runs long.
    [ -d "$corpus" ] && cp -r "$corpus/." "$work/" 2>/dev/null
    if "$bin" -max_total_time="${FUZZ_SECONDS:-20}" -timeout=10 -rss_limit_mb=2048 \
        -artifact_prefix="$OUT/$name-" "$work" >"$log" 2>&1; then
        echo "PASS fuzz/$name $(grep -o 'exec/s: [0-9]*' "$log" | tail -n 1)" >>"$results"
    else
        echo "FAIL fuzz/$name" >>"$results"
        tail -n 30 "$log" | sed 's/^/    /' >"$OUT/fail-fuzz-$name"
    fi
}

# Runs FN on each line of stdin, $JOBS at a time.
run_parallel() {
    running=0
    while read -r arg; do
        "$1" "$arg" &
        running=$((running + 1))
        if [ $running -ge "$JOBS" ]; then
            wait
            running=0
        fi
    done
    wait
}

echo "== unit tests ($BUILD/asan/gi-tests)"
"$BUILD/asan/gi-tests" --list | grep -E "$PATTERN" >"$OUT/unit-list"
# Parallel, one process per test (a crash fails only that test).
run_parallel run_unit <"$OUT/unit-list"

echo "== integration tests"
for s in "$SRC"/tests/integration/*.sh; do
    [ -f "$s" ] || continue
    [ "$(basename "$s")" = lib.sh ] && continue # sourced by the tests, not one
    echo "$(basename "$s" .sh)" | grep -Eq "$PATTERN" || continue
    run_integration "$s"
done

echo "== fuzz targets (short runs)"
# $JOBS at a time, like the unit tests: each target is one process on one
# core for FUZZ_SECONDS, so the phase takes targets / JOBS runs, not one
# per target.
for f in "$BUILD"/fuzz/fuzz_*; do
    [ -x "$f" ] || continue
    basename "$f" | grep -Eq "$PATTERN" || continue
    echo "$f"
done | run_parallel run_fuzz

sort -k2 "$results" | while read -r status name rest; do
    printf '%-5s %-50s %s\n' "$status" "$name" "$rest"
done
for f in "$OUT"/fail-*; do
    [ -f "$f" ] || continue
    echo "--- $(basename "$f" | sed 's/^fail-//')"
    cat "$f"
done
passed=$(grep -c '^PASS' "$results")
failed=$(grep -c '^FAIL' "$results")
skipped=$(grep -c '^SKIP' "$results")
[ "$skipped" -gt 0 ] && echo "($skipped skipped)"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
