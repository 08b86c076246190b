# deploy/Containerfile and deploy/kubernetes/gi-farm.yaml, as far as this
# machine can check them without a container engine or a cluster:
# - the image installs the package of every library the three programs link
#   (their ELF NEEDED entries, mapped to Debian packages by dpkg -S);
# - the manifest's images carry this build's version, and its pods run as
#   the image's user and group;
# - the command lines and environment of its two containers (each `args:`
#   line, gi-farmd's first) run as they are, with only the volumes' paths and
#   the service's address mapped to this machine: the worker joins and a job
#   renders to gi render's bytes; the worker's grace period outlasts its drain.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/farm/lib.sh"
CF="$SRC/deploy/Containerfile"
K8S="$SRC/deploy/kubernetes/gi-farm.yaml"

if command -v dpkg >/dev/null && command -v readelf >/dev/null; then
    for p in gi gi-farmd gi-worker; do
        bin="$BUILD/release/$p"
        for so in $(readelf -d "$bin" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'); do
            path=$(ldd "$bin" | awk -v so="$so" '$1 == so {print $3}')
            [ -n "$path" ] || fail "$p: ldd does not resolve $so"
            pkg=$(dpkg -S "$(readlink -f "$path")" 2>/dev/null || dpkg -S "$path" 2>/dev/null) ||
                fail "$p: no package owns $path ($so)"
            pkg=$(echo "$pkg" | head -n 1 | cut -d: -f1)
            case $pkg in libc6) continue ;; esac # in every Debian image
            grep -q "^ .*[[:space:]]$pkg\([[:space:]]\|$\)" "$CF" ||
                fail "$p links $so (package $pkg), which deploy/Containerfile does not install"
        done
    done
fi

# The pods' user is the image's, and the image names its group: USER
# UID:GID, the group created with that gid and the user with both.
user=$(sed -n 's/^USER \([0-9]*\):\([0-9]*\)$/\1 \2/p' "$CF")
uid=${user% *} gid=${user#* }
[ -n "$user" ] || fail "deploy/Containerfile has no USER UID:GID line"
grep -q "groupadd --gid $gid " "$CF" && grep -q "useradd --uid $uid --gid $gid " "$CF" ||
    fail "deploy/Containerfile does not create user $uid in group $gid"
for k in runAsUser:$uid runAsGroup:$gid fsGroup:$gid; do
    [ "$(grep -c "^ *${k%%:*}: ${k#*:}\$" "$K8S")" -eq 2 ] ||
        fail "the manifest's ${k%%:*} is not the image's ${k#*:} in both pods"
done

version=$("$GI" --version | awk '{print $2}')
[ "$(grep -c "image: gi-farm:$version\$" "$K8S")" -eq 2 ] ||
    fail "the manifest's images are not gi-farm:$version"
grep -q "gi-farm:$version " "$CF" || fail "the Containerfile's example tag is not $version"

# args LINE: the Nth `args:` line's words, one a line, with this machine's
# paths and addresses for the pod's.
args() {
    sed -n '/^ *args: \[/p' "$K8S" | sed -n "$1p" | sed 's/^ *args: \[//; s/\] *$//' |
        sed 's/", "/\n/g; s/"//g' |
        sed "s#^/var/lib/gi-farmd\$#$TMP/state#; s#^/var/cache/gi-worker\$#$TMP/cache#;
             s#^0.0.0.0:707[01]\$#127.0.0.1:0#; s#^gi-farmd:7071\$#\$WADDR#"
}
[ "$(sed -n '/^ *args: \[/p' "$K8S" | wc -l)" -eq 2 ] || fail "not two args lines"
args 1 >"$TMP/farmd.args"
args 2 >"$TMP/worker.args"
grep -qx -- "--state" "$TMP/farmd.args" && grep -qx -- "--connect" "$TMP/worker.args" ||
    fail "the args lines are not gi-farmd's then gi-worker's"
drain=$(grep -A1 -x -- "--drain-seconds" "$TMP/worker.args" | tail -n 1)
grace=$(grep "terminationGracePeriodSeconds:" "$K8S" | sed -n 2p | awk '{print $2}')
[ -n "$drain" ] && [ "$grace" -gt "$drain" ] ||
    fail "the worker's grace period ($grace s) does not outlast its drain ($drain s)"

# The secrets as the pods get them: environment variables.
secret=$(head -c 32 /dev/urandom | base64)
token=$(head -c 32 /dev/urandom | base64)
set -f
# shellcheck disable=SC2046
start_farmd "$TMP/state" "$TMP/farmd.log" env GI_FARM_SECRET="$secret" GI_FARM_TOKEN="$token" -- \
    $(cat "$TMP/farmd.args") # the manifest's --state and --listen-* come last: they count
set +f
export GI_FARM="http://$API" GI_FARM_TOKEN="$token"
unset GI_FARM_TOKEN_FILE GI_FARM_SECRET_FILE
set -f
# shellcheck disable=SC2046
start_worker "$TMP/worker.log" env GI_FARM_SECRET="$secret" -- \
    $(sed "s#^\$WADDR\$#$WADDR#" "$TMP/worker.args") --procs 1
set +f
wait_workers 1
cornell_job "$TMP/pt.json" 9 32 32 16
"$GI" submit "$TMP/pt.json" --wait --out "$TMP/farm" --progress none >"$TMP/submit.log" 2>&1 ||
    { cat "$TMP/submit.log"; fail "the job did not render"; }
cmp "$TMP/pt.json.ref/img.exr" "$TMP/farm/img.exr" || fail "the farm's image differs from gi render"
stop_farmd "$TMP/farmd.log"
echo ok
