# Sourced by integration tests. The runner sets GI (ASan build of gi),
# GI_RELEASE (optimized build), IMGTOOL, SRC (source tree), TMP (scratch).
set -eu
fail() {
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
