#!/bin/sh
# make fuzz: runs every fuzz target for a long time (FUZZ_SECONDS, default
# 600 each) on a copy of its corpus; new interesting inputs are kept in
# build/fuzz/corpus-<target>/ (not in the tree). Crashes are saved there too.
#   tests/fuzz/run.sh BUILD_FUZZ_DIR long
set -eu
BIN=$1
SRC=$(cd "$(dirname "$0")/../.." && pwd)
SECS=${FUZZ_SECONDS:-600}
status=0
for f in "$BIN"/fuzz_*; do
    [ -x "$f" ] || continue
    name=$(basename "$f")
    work="$BIN/corpus-${name#fuzz_}"
    mkdir -p "$work"
    cp -r "$SRC/tests/fuzz/corpus/${name#fuzz_}/." "$work/" 2>/dev/null || true
    echo "== $name for ${SECS}s"
    if ! "$f" -max_total_time="$SECS" -timeout=10 -rss_limit_mb=2048 \
        -artifact_prefix="$work/" "$work"; then
        echo "$name: FAILED (artifacts in $work)"
        status=1
    fi
done
exit $status
