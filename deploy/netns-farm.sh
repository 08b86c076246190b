#!/bin/sh
# A multi-host test farm on one machine: network namespaces joined by a
# bridge, one coordinator host and N worker hosts with their own addresses.
#
#   deploy/netns-farm.sh up PREFIX [WORKERS]   create PREFIX-c, PREFIX-w1..wN
#   deploy/netns-farm.sh down PREFIX           kill their processes, delete them
#   deploy/netns-farm.sh cut PREFIX HOST       unplug HOST's cable (c, w1, ...)
#   deploy/netns-farm.sh plug PREFIX HOST      plug it back
#   deploy/netns-farm.sh addr PREFIX HOST      print HOST's address
#   deploy/netns-farm.sh exec PREFIX HOST CMD...   run CMD on HOST
#
# Layout: the bridge br0 lives in its own namespace PREFIX-hub, so nothing
# touches the machine's own network; each host namespace has lo and eth0,
# a veth whose other end (named after the host) is a port of br0. Addresses
# are $GI_NETNS_NET.1 for the coordinator and .11, .12, ... for workers
# (GI_NETNS_NET defaults to 10.77.0; the hosts reach only each other).
# Cutting a host sets its bridge port down: the host keeps its address and
# sockets, packets are lost both ways until it is plugged back, as when a
# cable or switch port fails. Needs root (CAP_NET_ADMIN) and iproute2.
set -eu
NET=${GI_NETNS_NET:-10.77.0}
cmd=${1:-}
P=${2:-}
[ -n "$cmd" ] && [ -n "$P" ] || { sed -n '2,19p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
case "$P" in *[!a-zA-Z0-9_-]* | ?????????????*) echo "netns-farm: PREFIX must be 1-12 of [a-zA-Z0-9_-]" >&2; exit 2 ;; esac

hosts() { # the host names, coordinator first
    echo c
    n=1
    while [ "$n" -le "$1" ]; do echo "w$n"; n=$((n + 1)); done
}

addr_of() {
    case "$1" in
    c) echo "$NET.1" ;;
    w*) echo "$NET.$((10 + ${1#w}))" ;;
    *) echo "netns-farm: unknown host $1" >&2; exit 2 ;;
    esac
}

case "$cmd" in
up)
    workers=${3:-3}
    ip netns add "$P-hub"
    ip -n "$P-hub" link set lo up
    ip -n "$P-hub" link add br0 type bridge
    ip -n "$P-hub" link set br0 up
    for h in $(hosts "$workers"); do
        ip netns add "$P-$h"
        ip -n "$P-hub" link add "$h" type veth peer name eth0 netns "$P-$h"
        ip -n "$P-hub" link set "$h" master br0
        ip -n "$P-hub" link set "$h" up
        ip -n "$P-$h" link set lo up
        ip -n "$P-$h" addr add "$(addr_of "$h")/24" dev eth0
        ip -n "$P-$h" link set eth0 up
    done
    ;;
down)
    for ns in $(ip netns list | awk '{print $1}' | grep -E "^$P-(hub|c|w[0-9]+)\$" || true); do
        # Processes started in the host (ours, by construction): TERM, then KILL.
        pids=$(ip netns pids "$ns" 2>/dev/null || true)
        [ -n "$pids" ] && kill $pids 2>/dev/null || true
    done
    sleep 0.2
    for ns in $(ip netns list | awk '{print $1}' | grep -E "^$P-(hub|c|w[0-9]+)\$" || true); do
        pids=$(ip netns pids "$ns" 2>/dev/null || true)
        [ -n "$pids" ] && kill -9 $pids 2>/dev/null || true
        ip netns del "$ns" 2>/dev/null || true
    done
    ;;
cut) ip -n "$P-hub" link set "${3:?host}" down ;;
plug) ip -n "$P-hub" link set "${3:?host}" up ;;
addr) addr_of "${3:?host}" ;;
exec)
    h=${3:?host}
    shift 3
    exec ip netns exec "$P-$h" "$@"
    ;;
*) sed -n '2,22p' "$0"; exit 2 ;;
esac
