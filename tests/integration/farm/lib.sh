# Sourced by the farm_*.sh integration tests (after ../lib.sh). Starts
# gi-farmd and gi-worker processes, remembers their pids, and cleans up
# (processes and network namespaces) on exit, whether the test passed or not.
FARMD=${FARMD:-$BUILD/asan/gi-farmd}
WORKER=${WORKER:-$BUILD/release/gi-worker}
WORKER_ASAN=$BUILD/asan/gi-worker
RAWPEER=$BUILD/release/tools/gi_rawpeer
NETNS=$SRC/deploy/netns-farm.sh
FARM_PIDS=""
WORKER_PIDS="" # the gi-worker processes started (pools_stop)
FARM_NS=""
FARM_EXEC="" # a prefix that runs API clients where the API is reachable (a namespace)

farm_cleanup() {
    for p in $FARM_PIDS; do kill -9 "$p" 2>/dev/null || true; done
    [ -n "$FARM_NS" ] && sh "$NETNS" down "$FARM_NS" >/dev/null 2>&1 || true
}
trap farm_cleanup EXIT INT TERM

# Secrets in $TMP, passed through the environment as files.
make_secrets() {
    head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \n' >"$TMP/secret"
    head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \n' >"$TMP/token"
    chmod 600 "$TMP/secret" "$TMP/token"
    export GI_FARM_SECRET_FILE="$TMP/secret" GI_FARM_TOKEN_FILE="$TMP/token"
}

# show_on_failure LOG: fail() shows its last lines (once, however often the
# process behind it is restarted).
show_on_failure() {
    case " ${FAIL_LOGS:-} " in *" $1 "*) ;; *) FAIL_LOGS="${FAIL_LOGS:-} $1" ;; esac
}

# start_farmd STATE LOG [prefix command...] -- [gi-farmd options...]
# Loopback on kernel-chosen ports unless options say otherwise; sets
# FARMD_PID, API (host:port) and WADDR (host:port).
start_farmd() {
    state=$1
    log=$2
    shift 2
    pre=""
    while [ $# -gt 0 ] && [ "$1" != "--" ]; do pre="$pre $1"; shift; done
    [ $# -gt 0 ] && shift
    rm -f "$state/addresses"
    show_on_failure "$log"
    # shellcheck disable=SC2086
    $pre "$FARMD" --state "$state" --listen-workers 127.0.0.1:0 --listen-api 127.0.0.1:0 "$@" \
        >>"$log" 2>&1 &
    FARMD_PID=$!
    FARM_PIDS="$FARM_PIDS $FARMD_PID"
    i=0
    while [ ! -s "$state/addresses" ]; do
        i=$((i + 1))
        [ $i -lt 200 ] || { cat "$log"; fail "gi-farmd did not start"; }
        kill -0 "$FARMD_PID" 2>/dev/null || { cat "$log"; fail "gi-farmd exited"; }
        sleep 0.05
    done
    API=$(awk '$1 == "api" {print $2}' "$state/addresses")
    WADDR=$(awk '$1 == "workers" {print $2}' "$state/addresses")
    export GI_FARM="http://$API"
}

# render_refs NAME...: `gi render` of $TMP/NAME.json into $TMP/ref-NAME, the
# outputs a farm run of it must match.
render_refs() {
    for j in "$@"; do
        "$GI_RELEASE" render "$TMP/$j.json" --workers 1 --out "$TMP/ref-$j" --progress none \
            >/dev/null 2>&1 || fail "gi render $j"
    done
}

# start_worker LOG [prefix command...] -- [gi-worker options...]; sets WORKER_PID.
start_worker() {
    log=$1
    shift
    pre=""
    while [ $# -gt 0 ] && [ "$1" != "--" ]; do pre="$pre $1"; shift; done
    [ $# -gt 0 ] && shift
    show_on_failure "$log"
    # shellcheck disable=SC2086
    $pre "$WORKER" --backoff-max 0.5 "$@" >>"$log" 2>&1 &
    WORKER_PID=$!
    WORKER_PIDS="$WORKER_PIDS $WORKER_PID"
    FARM_PIDS="$FARM_PIDS $WORKER_PID"
}

# wait_workers N: until N workers are connected and active (a test that
# needs work spread over hosts must not submit before they are all there).
wait_workers() {
    n=0
    until [ "$(${FARM_EXEC:-} "$GI" workers 2>/dev/null | grep -c ' active ')" -ge "$1" ]; do
        n=$((n + 1))
        [ $n -lt 300 ] || { ${FARM_EXEC:-} "$GI" workers; fail "$1 workers did not connect"; }
        sleep 0.1
    done
}

# api PATH [curl options]: an authenticated API call (prints the body).
api() {
    path=$1
    shift
    $FARM_EXEC curl -sS --max-time 30 -H "Authorization: Bearer $(cat "$GI_FARM_TOKEN_FILE")" "$@" \
        "$GI_FARM$path"
}

# A task count of a job: jnum ID KEY (total, merged, retries, results_this_run,
# resumed_merged, late_results, lease_expiries, ...).
jnum() {
    api "/api/v1/jobs/$1" | sed -n 's/.*"tasks":{\([^}]*\)}.*/\1/p' | tr ',' '\n' |
        awk -F: -v k="\"$2\"" '$1 == k {print $2}'
}

jstate() {
    api "/api/v1/jobs/$1" | grep -o '"state":"[a-z]*"' | head -n 1 | cut -d'"' -f4
}

# unended ID: the job is running, or finishing (its outputs being written)
unended() {
    case $(jstate "$1") in running | finishing) return 0 ;; *) return 1 ;; esac
}

# wait_state ID STATE SECONDS
wait_state() {
    n=0
    while [ "$(jstate "$1")" != "$2" ]; do
        n=$((n + 1))
        [ $n -lt $(($3 * 10)) ] || { api "/api/v1/jobs/$1"; echo; fail "job $1 not $2 after $3 s"; }
        sleep 0.1
    done
}

# A metric's value from /metrics.
metric() {
    api /metrics | awk -v m="$1" '$1 == m {print $2}'
}

# api_conns [STATE]: gi-farmd's API connections (local port that of $API)
# in the kernel's TCP STATE, hex as /proc/net/tcp has it (default: 01,
# established, and 08, close-wait: the client sent its end).
api_conns() {
    port=$(printf '%04X' "${API##*:}")
    awk -v p=":$port" -v st="${1:-01 08}" 'NR > 1 && substr($2, length($2) - 4) == p &&
        index(" " st " ", " " $4 " ") {n++} END {print n + 0}' /proc/net/tcp
}

# wait_api_conns N: until gi-farmd has N API connections open at most (10 s).
wait_api_conns() {
    n=0
    until [ "$(api_conns)" -le "$1" ]; do
        n=$((n + 1))
        [ $n -lt 200 ] || fail "gi-farmd still has $(api_conns) API connections open ($1 expected)"
        sleep 0.05
    done
}

# stop_farmd LOG: SIGTERM, a clean exit (status 0) and, under ASan, no leaks.
stop_farmd() {
    kill -TERM "$FARMD_PID"
    farmd_stopped "$1"
}

# farmd_stopped LOG: gi-farmd, sent SIGTERM, exits cleanly.
farmd_stopped() {
    wait "$FARMD_PID" || { tail -n 30 "$1"; fail "gi-farmd exited with status $? on SIGTERM"; }
    ! grep -q "LeakSanitizer\|AddressSanitizer\|runtime error" "$1" || { cat "$1"; fail "sanitizer report"; }
}

# Needs root and network namespaces, or exits 77 (skipped) saying why.
need_netns() {
    [ "$(id -u)" = 0 ] || skip "multi-host tests need root for network namespaces"
    command -v ip >/dev/null 2>&1 || skip "iproute2 (ip) is not installed"
    probe="giprobe$$"
    ip netns add "$probe" 2>/dev/null || skip "cannot create network namespaces here"
    ip netns del "$probe"
}

# netns_up PREFIX WORKERS: the namespace farm (deleted on exit).
netns_up() {
    FARM_NS=$1
    sh "$NETNS" down "$1" >/dev/null 2>&1 || true
    sh "$NETNS" up "$1" "$2" || fail "cannot build the namespace farm"
}

# The job's last checkpoint: jckpt ID KEY (seq, merged).
jckpt() {
    api "/api/v1/jobs/$1" | sed -n 's/.*"checkpoint":{\([^}]*\)}.*/\1/p' | tr ',' '\n' |
        awk -F: -v k="\"$2\"" '$1 == k {print $2}'
}

# wait_log FILE PATTERN: until the log has a line matching PATTERN (10 s).
wait_log() {
    n=0
    until grep -q -- "$2" "$1"; do
        n=$((n + 1))
        [ $n -lt 200 ] || { tail -n 30 "$1"; fail "not logged: $2"; }
        sleep 0.05
    done
}

# netns_farm PREFIX [gi-farmd options...]: a coordinator host and three
# worker hosts (one process each) in network namespaces. Sets C (the
# coordinator's address) and FARM_EXEC (runs API clients on its host).
netns_farm() {
    P=$1
    shift
    need_netns
    make_secrets
    netns_up "$P" 3
    C=$(sh "$NETNS" addr "$P" c)
    FARM_EXEC="ip netns exec $P-c"
    start_farmd "$TMP/state" "$TMP/farmd.log" ip netns exec "$P-c" -- \
        --listen-workers "$C:7071" --listen-api "$C:7070" "$@"
    for i in 1 2 3; do
        start_worker "$TMP/w$i.log" ip netns exec "$P-w$i" -- --connect "$C:7071" --procs 1 \
            --cache "$TMP/cache$i" --name "host$i"
    done
    wait_workers 3
}

# cornell_job FILE SEED WIDTH HEIGHT SPP [PASS_SPP]: a Cornell box pt job
# writing img.exr, and its reference rendering by `gi render` into FILE.ref/.
cornell_job() {
    write_job "$1" <<JOB
{
  "scene": "$SRC/scenes/cornell-box/scene.json",
  "method": "pt",
  "seed": $2,
  "image": {"width": $3, "height": $4},
  "pt": {"spp": $5, "tile": 16, "pass_spp": ${6:-8}},
  "outputs": {"exr": "img.exr"}
}
JOB
    "$GI_RELEASE" render "$1" --workers 2 --out "$1.ref" --progress none >/dev/null 2>&1 ||
        fail "reference render of $1"
}

# wait_merged ID DIVISOR [checkpoint]: until at least total/DIVISOR tasks are
# merged (or, with "checkpoint", are in the last checkpoint: wait_checkpoint),
# and the job is still running (for a test that must act mid-job). Sets
# merged and total.
wait_merged() {
    t0=$(date +%s)
    while :; do
        merged=$(jnum "$1" merged)
        total=$(jnum "$1" total)
        [ "${total:-0}" -gt 0 ] && [ "${merged:-0}" -ge $((total / $2)) ] && break
        [ $(($(date +%s) - t0)) -lt 120 ] || fail "job $1 did not progress in 120 s"
        sleep 0.05
    done
    [ "${3:-}" = checkpoint ] && wait_checkpoint "$1" $((total / $2))
    unended "$1" || fail "job $1 ended too soon; make it longer"
}

# pools_stop, pools_cont: stop (SIGSTOP) and continue the pool children of
# the test's workers. No task runs meanwhile, so a job cannot progress nor
# end, while the workers themselves go on heartbeating: no lease expires and
# no task runs twice. (Their children exist once they have connected.)
pools_stop() {
    STOPPED_KIDS=$(for w in $WORKER_PIDS; do pgrep -P "$w" || true; done | tr '\n' ' ')
    [ -n "$STOPPED_KIDS" ] || fail "no pool children to stop"
    # shellcheck disable=SC2086
    kill -STOP $STOPPED_KIDS
}
pools_cont() {
    # shellcheck disable=SC2086
    kill -CONT $STOPPED_KIDS
}

# wait_checkpoint ID N: once N tasks of the job are merged, until its last
# checkpoint holds at least N (sets merged to what it holds). A periodic
# checkpoint comes --checkpoint seconds after the last one, or 20 times as
# long as that one took (gi_jobrun_checkpoint_interval): on a busy disk one
# slow checkpoint spaces the next by seconds, time enough for a short job to
# end in between. So the pools are stopped meanwhile.
wait_checkpoint() {
    pools_stop
    t0=$(date +%s)
    until [ "$(jckpt "$1" merged)" -ge "$2" ] 2>/dev/null; do
        [ $(($(date +%s) - t0)) -lt 120 ] ||
            { api "/api/v1/jobs/$1"; fail "job $1: no checkpoint of $2 tasks in 120 s"; }
        unended "$1" || break
        sleep 0.05
    done
    merged=$(jckpt "$1" merged)
    pools_cont
}

# need_own_disk SIZE: root and a tmpfs in a mount namespace, or exits 77
# (skipped). Writes $TMP/own_disk.sh: `sh $TMP/own_disk.sh DIR COMMAND...`
# runs COMMAND with a tmpfs of SIZE of its own on DIR (a disk to fill up or
# turn read-only under it).
need_own_disk() {
    [ "$(id -u)" = 0 ] || skip "a disk of its own needs root (a tmpfs in a mount namespace)"
    command -v unshare >/dev/null 2>&1 || skip "unshare (util-linux) is not installed"
    mkdir -p "$TMP/probe"
    unshare -m sh -c 'mount -t tmpfs -o size=64k tmpfs "$0"' "$TMP/probe" 2>/dev/null ||
        skip "cannot mount a tmpfs in a mount namespace here"
    cat >"$TMP/own_disk.sh" <<EOF
dir=\$1
shift
exec unshare -m sh -c 'mount -t tmpfs -o size=$1 tmpfs "\$0" && exec "\$@"' "\$dir" "\$@"
EOF
}

# fault_runs IDS...: every attempt (0-7) of those task ids, as the fault
# hooks name runs (GI_FAULT_CRASH_TASK=$(fault_runs 10 11)).
fault_runs() {
    for t in "$@"; do for k in 0 1 2 3 4 5 6 7; do printf '%s:%s,' "$t" "$k"; done; done |
        sed 's/,$//'
}

# excluded ID: the workers excluded from job ID now, by name, sorted, each
# followed by a space ("w1 w2 ").
excluded() {
    api "/api/v1/jobs/$1" | tr '{' '\n' | sed -n 's/^"worker":"\([^"]*\)","excluded":true,.*/\1/p' |
        sort | tr '\n' ' '
}
