# Sourced by the farm benchmark drivers (BIN: the build's directory): a
# temporary directory $T, removed at exit with the processes listed in
# $PIDS; the farm's secret and token; gi-farmd on free loopback ports
# (FARMD_ARGS adds options), its process in FARMD_PID, its API in GI_FARM
# and its worker port in WADDR.
T=$(mktemp -d "${TMPDIR:-/tmp}/gi-bench-farm.XXXXXX")
PIDS=""
cleanup() {
    for p in $PIDS; do kill "$p" 2>/dev/null || true; done
    wait 2>/dev/null || true
    rm -rf "$T"
}
trap cleanup EXIT INT TERM
head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \n' >"$T/secret"
head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \n' >"$T/token"
chmod 600 "$T/secret" "$T/token"
export GI_FARM_SECRET_FILE="$T/secret" GI_FARM_TOKEN_FILE="$T/token" GI_LOG=warn
# shellcheck disable=SC2086
"$BIN/gi-farmd" --state "$T/state" --listen-workers 127.0.0.1:0 --listen-api 127.0.0.1:0 \
    ${FARMD_ARGS:-} >"$T/farmd.log" 2>&1 &
FARMD_PID=$!
PIDS="$PIDS $FARMD_PID"
while [ ! -s "$T/state/addresses" ]; do sleep 0.05; done
export GI_FARM="http://$(awk '$1 == "api" {print $2}' "$T/state/addresses")"
WADDR=$(awk '$1 == "workers" {print $2}' "$T/state/addresses")
