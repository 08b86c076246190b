#!/bin/sh
# Builds deploy/Containerfile with podman and checks the image the way the
# Kubernetes manifest runs it (docs/farm.md, "Containers"). Not part of
# `make test`: it needs root, podman and a few minutes. From the repository:
#
#   sh scripts/image-check.sh                 debian:12 and -slim from the registry
#   sh scripts/image-check.sh --debootstrap   no registry: local stand-ins for them
#
# It checks: the image runs as 10001:10001; `gi render` of a small Cornell-box
# job in a read-only container gives the host's bytes (build/release/gi, if
# built); gi-farmd and a gi-worker in two read-only containers (no
# capabilities, state and cache on volumes owned by group 10001, the secrets
# in the environment, the worker limited to one CPU) render the same job to
# the same bytes for `gi submit` from a third container; the worker reports
# one process and one core; nothing is written outside the volumes and /tmp;
# both stop with status 0 on SIGTERM. Containers and scratch are removed at
# the end; the images stay.
set -eu
cd "$(dirname "$0")/.."

stand_ins=0
case ${1:-} in
    --debootstrap) stand_ins=1 ;;
    "") ;;
    *) echo "usage: sh scripts/image-check.sh [--debootstrap]" >&2; exit 2 ;;
esac
die() {
    echo "image-check: $*" >&2
    exit 1
}
[ "$(id -u)" = 0 ] || die "run it as root (its volumes belong to uid 10001)"
command -v podman >/dev/null || die "podman is not installed"

VERSION=$(sed -n 's/^#define GI_VERSION "\(.*\)"$/\1/p' common/gi_version.h)
IMAGE=gi-farm:$VERSION
T=$(mktemp -d /var/tmp/gi-image-check.XXXXXX)
NAME=gi-check-$$
cleanup() {
    podman rm -f -t 0 "$NAME-farmd" "$NAME-worker" >/dev/null 2>&1 || true
    rm -rf "$T"
}
trap cleanup EXIT
trap 'exit 1' INT TERM
fail() { die "FAIL: $*"; }
ok() { echo "image-check: ok: $*"; }

# Stand-ins for Docker Hub's debian:12 and debian:12-slim: minbase systems
# (as debuerreotype builds them) with empty package lists, apt's cache
# cleaned after each install, the security suite, and for slim the dpkg
# filter that leaves out docs, man pages and locales. They only approximate the real images.
stand_in() { # TAG SLIM
    r=$T/rootfs-$1
    debootstrap --variant=minbase bookworm "$r" http://deb.debian.org/debian \
        >"$T/debootstrap-$1.log" 2>&1 ||
        { tail -n 20 "$T/debootstrap-$1.log"; fail "debootstrap for debian:$1"; }
    rm -rf "$r"/var/lib/apt/lists/* "$r"/var/cache/apt/archives/*.deb "$r"/etc/apt/sources.list
    mkdir -p "$r"/var/lib/apt/lists/partial
    cat >"$r"/etc/apt/sources.list.d/debian.sources <<'EOF'
Types: deb
URIs: http://deb.debian.org/debian
Suites: bookworm bookworm-updates
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg

Types: deb
URIs: http://deb.debian.org/debian-security
Suites: bookworm-security
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
EOF
    echo 'Acquire::Languages "none";' >"$r"/etc/apt/apt.conf.d/docker-no-languages
    cat >"$r"/etc/apt/apt.conf.d/docker-clean <<'EOF'
DPkg::Post-Invoke { "rm -f /var/cache/apt/archives/*.deb /var/cache/apt/*.bin || true"; };
APT::Update::Post-Invoke { "rm -f /var/cache/apt/archives/*.deb /var/cache/apt/*.bin || true"; };
Dir::Cache::pkgcache "";
Dir::Cache::srcpkgcache "";
EOF
    if [ "$2" = 1 ]; then
        printf '%s\n' 'path-exclude /usr/share/doc/*' 'path-include /usr/share/doc/*/copyright' \
            'path-exclude /usr/share/man/*' 'path-exclude /usr/share/info/*' \
            'path-exclude /usr/share/locale/*' 'path-include /usr/share/locale/locale.alias' \
            >"$r"/etc/dpkg/dpkg.cfg.d/docker
        find "$r"/usr/share/doc -mindepth 2 ! -name copyright ! -type d -delete
        rm -rf "$r"/usr/share/man/* "$r"/usr/share/info/*
        find "$r"/usr/share/locale -mindepth 1 -maxdepth 1 ! -name locale.alias -exec rm -rf {} +
    fi
    tar -C "$r" -c . |
        podman import --change 'CMD ["bash"]' - "docker.io/library/debian:$1" >/dev/null
    rm -rf "$r"
    ok "stand-in docker.io/library/debian:$1"
}
pull=missing
if [ $stand_ins = 1 ]; then
    command -v debootstrap >/dev/null || fail "debootstrap is not installed"
    stand_in 12 0
    stand_in 12-slim 1
    pull=never
fi

start=$(date +%s)
podman build --pull=$pull -f deploy/Containerfile -t "$IMAGE" . >"$T/build.log" 2>&1 ||
    { tail -n 40 "$T/build.log"; fail "podman build"; }
size=$(podman image inspect -f '{{.Size}}' "$IMAGE")
ok "built $IMAGE in $(($(date +%s) - start)) s, $((size / 1000000)) MB"

run() { podman run --rm "$@"; }
[ "$(run "$IMAGE" gi --version)" = "gi $VERSION" ] || fail "gi --version in the image"
[ "$(run "$IMAGE" id -u):$(run "$IMAGE" id -g)" = 10001:10001 ] ||
    fail "the image's user is not 10001:10001"
ok "gi $VERSION, user 10001:10001"

# As the manifest runs the containers: read-only root, /tmp a scratch
# volume, no capabilities, no privilege escalation.
SEC="--read-only --read-only-tmpfs=false --tmpfs /tmp --cap-drop ALL
     --security-opt no-new-privileges --user 10001:10001 --group-add 10001"
mkdir -p "$T/job" "$T/out" "$T/state" "$T/cache"
cp -r scenes/cornell-box "$T/job/"
cat >"$T/job/pt.json" <<'EOF'
{
  "scene": "cornell-box/scene.json",
  "method": "pt",
  "seed": 9,
  "image": {"width": 64, "height": 64},
  "pt": {"spp": 16, "tile": 16, "pass_spp": 8},
  "outputs": {"exr": "img.exr", "png": "img.png"}
}
EOF
chmod -R a+rX "$T/job"
# Volumes as Kubernetes' fsGroup leaves them: root's, group 10001, setgid.
chown root:10001 "$T/out" "$T/state" "$T/cache"
chmod 2775 "$T/out" "$T/state"
chmod 2777 "$T/cache"

# gi render keeps its batch files under $TMPDIR, /var/tmp by default: read-only here.
# shellcheck disable=SC2086
run $SEC -e TMPDIR=/tmp -v "$T/job:/job:ro" -v "$T/out:/out" "$IMAGE" \
    gi render /job/pt.json --out /out/render --progress none >"$T/render.log" 2>&1 ||
    { cat "$T/render.log"; fail "gi render in a read-only container"; }
if [ -x build/release/gi ]; then
    build/release/gi render "$T/job/pt.json" --out "$T/host" --progress none >/dev/null 2>&1 ||
        fail "gi render on the host"
    cmp "$T/host/img.exr" "$T/out/render/img.exr" ||
        fail "the container's render differs from the host's"
    ok "gi render in a read-only container: the host's bytes"
else
    ok "gi render in a read-only container (no build/release/gi to compare with)"
fi

secret=$(head -c 32 /dev/urandom | base64)
token=$(head -c 32 /dev/urandom | base64)
# shellcheck disable=SC2086
GI_FARM_SECRET=$secret GI_FARM_TOKEN=$token podman run -d --name "$NAME-farmd" --network host $SEC \
    -e GI_FARM_SECRET -e GI_FARM_TOKEN -v "$T/state:/var/lib/gi-farmd" "$IMAGE" \
    gi-farmd --state /var/lib/gi-farmd --listen-workers 127.0.0.1:0 --listen-api 127.0.0.1:0 \
    >/dev/null
n=0
until [ -s "$T/state/addresses" ]; do
    n=$((n + 1))
    [ $n -lt 100 ] || { podman logs "$NAME-farmd"; fail "gi-farmd did not start"; }
    sleep 0.1
done
API=$(awk '$1 == "api" {print $2}' "$T/state/addresses")
WADDR=$(awk '$1 == "workers" {print $2}' "$T/state/addresses")
cpus="--cpus 1"
# shellcheck disable=SC2086
GI_FARM_SECRET=$secret podman run -d --name "$NAME-worker" --network host $cpus $SEC \
    -e GI_FARM_SECRET -v "$T/cache:/var/cache/gi-worker" "$IMAGE" \
    gi-worker --connect "$WADDR" --cache /var/cache/gi-worker --name "$NAME" \
    >/dev/null 2>"$T/worker.err" || {
    # cgroup v1 without the cpu controller, or rootless on v1, refuse --cpus.
    cat "$T/worker.err"
    echo "image-check: --cpus refused here; the worker runs without a CPU limit"
    podman rm -f "$NAME-worker" >/dev/null 2>&1 || true
    cpus=""
    GI_FARM_SECRET=$secret podman run -d --name "$NAME-worker" --network host $SEC \
        -e GI_FARM_SECRET -v "$T/cache:/var/cache/gi-worker" "$IMAGE" \
        gi-worker --connect "$WADDR" --cache /var/cache/gi-worker --name "$NAME" >/dev/null
}
client() {
    # shellcheck disable=SC2086
    GI_FARM_TOKEN=$token podman run --rm --network host $SEC -e GI_FARM="http://$API" \
        -e GI_FARM_TOKEN -v "$T/job:/job:ro" -v "$T/out:/out" "$IMAGE" "$@"
}
n=0
until client gi workers 2>/dev/null | grep -q "^$NAME .* active "; do
    n=$((n + 1))
    [ $n -lt 30 ] || { podman logs "$NAME-worker"; fail "the worker did not join"; }
    sleep 1
done
if [ -n "$cpus" ]; then
    line=$(client gi workers | grep "^$NAME ")
    [ "$(echo "$line" | awk '{print $4, $5}')" = "1 1" ] ||
        fail "the worker limited to one CPU does not report 1 process, 1 core: $line"
    ok "the worker with --cpus 1: 1 process, 1 core"
fi
client gi submit /job/pt.json --wait --out /out/farm --progress none >"$T/submit.log" 2>&1 ||
    { cat "$T/submit.log"; fail "gi submit"; }
cmp "$T/out/render/img.exr" "$T/out/farm/img.exr" ||
    fail "the farm's image differs from gi render's"
cmp "$T/out/render/img.png" "$T/out/farm/img.png" || fail "the farm's PNG differs from gi render's"
ok "gi-farmd and gi-worker in containers: gi render's bytes"

for c in farmd worker; do
    # Allowed (the manifest gives /tmp a volume), but worth knowing.
    podman exec "$NAME-$c" find /tmp -mindepth 1 | sed "s/^/image-check: gi-$c's \/tmp has /"
    podman exec "$NAME-$c" sh -c 'tr "\0" "\n" </proc/1/environ' | grep -q '^GI_FARM_[A-Z]*=.' &&
        fail "gi-$c left a secret in its environment"
done
[ -s "$T/state/journal" ] || fail "no journal in the state volume"
[ -d "$T/cache/batches" ] || fail "no cache in the cache volume"
ok "state and cache only on their volumes; the secrets cleared from the environment"

podman stop -t 150 "$NAME-worker" "$NAME-farmd" >/dev/null
for c in worker farmd; do
    rc=$(podman inspect -f '{{.State.ExitCode}}' "$NAME-$c")
    [ "$rc" = 0 ] || { podman logs "$NAME-$c" | tail -n 20; fail "gi-$c exited $rc on SIGTERM"; }
done
ok "both stop with status 0 on SIGTERM"
echo "image-check: all checks passed ($IMAGE)"
