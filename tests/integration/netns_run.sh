#!/usr/bin/env bash
# Runs a test binary on a small virtual network of its own: one network namespace per host
# (discovery server "ds", instructor "in", stations "s1" and "s2") and a switch namespace
# holding a bridge. ds, in and s1 are on the bridge (10.77.0.0/24); s2 is a far site
# (10.78.0.0/24) behind a router namespace "rt" whose link to it has 50 ms delay and 2 % loss
# each way. The delay and loss come from link_emulator.py between two TUN devices of the
# router (this kernel has no sch_netem; `tc qdisc add dev eth0 root netem delay 50ms loss 2%`
# would do the same). Addresses exist only inside these namespaces: the host's own
# interfaces, addresses, routes and sysctls are never touched. The test binary runs inside
# "in"; it finds the other namespaces and addresses in the environment (MICRODEX_NETNS_*,
# MICRODEX_ADDR_*). A partition is `ip -n $MICRODEX_NETNS_SWITCH link set s1 down`.
#
# Usage: netns_run.sh TEST_BINARY [ARGS...]. Exits 77 (CTest: skipped) with the reason when
# this machine cannot make network namespaces (not root, no CAP_NET_ADMIN, no TUN device).
# Every namespace and process in it is removed on exit, whatever the outcome.
set -u

binary=$1
shift

skip() {
  echo "SKIPPED: $*" >&2
  exit 77
}

[ "$(id -u)" -eq 0 ] || skip "needs root for ip netns (running as uid $(id -u))"
command -v ip >/dev/null || skip "needs iproute2 (ip)"
command -v tc >/dev/null || skip "needs iproute2 (tc)"

here=$(cd "$(dirname "$0")" && pwd)
prefix="mdx$$"
sw="${prefix}sw"
hosts=(ds in s1 s2 rt)
declare -A addr=([ds]=10.77.0.2 [in]=10.77.0.3 [s1]=10.77.0.11 [rt]=10.77.0.1 [s2]=10.78.0.12)

cleanup() {
  for h in "${hosts[@]}"; do
    ip netns pids "${prefix}${h}" 2>/dev/null | xargs -r kill -9 2>/dev/null
  done
  for h in "${hosts[@]}"; do ip netns del "${prefix}${h}" 2>/dev/null; done
  ip netns del "$sw" 2>/dev/null
  return 0
}
trap cleanup EXIT
trap 'exit 143' TERM INT

# Namespaces left by an earlier run killed with SIGKILL (their creator's pid is gone).
for ns in $(ip netns list 2>/dev/null | awk '{print $1}' | grep -E '^mdx[0-9]+' || true); do
  owner=$(echo "$ns" | sed -E 's/^mdx([0-9]+).*/\1/')
  if ! kill -0 "$owner" 2>/dev/null; then
    ip netns pids "$ns" 2>/dev/null | xargs -r kill -9 2>/dev/null
    ip netns del "$ns" 2>/dev/null
  fi
done

[ -c /dev/net/tun ] || skip "needs /dev/net/tun for the far site's slow link"
ip netns add "$sw" 2>/dev/null || skip "cannot create a network namespace (ip netns add failed)"
ip -n "$sw" link add br0 type bridge || skip "cannot create a bridge in a namespace"
ip -n "$sw" link set br0 up
ip -n "$sw" link set lo up
for h in "${hosts[@]}"; do
  ip netns add "${prefix}${h}" || skip "cannot create namespace ${prefix}${h}"
  ip -n "${prefix}${h}" link set lo up
done
# veth pair: "eth0" inside a host's namespace, "$h" on the switch (s2 hangs off the router).
for h in ds in s1 rt; do
  ns="${prefix}${h}"
  ip link add "${prefix}${h}a" netns "$ns" type veth peer name "${prefix}${h}b" netns "$sw" ||
    skip "cannot create veth pairs"
  ip -n "$ns" link set "${prefix}${h}a" name eth0
  ip -n "$sw" link set "${prefix}${h}b" name "$h"
  ip -n "$sw" link set "$h" master br0
  ip -n "$sw" link set "$h" up
  ip -n "$ns" addr add "${addr[$h]}/24" dev eth0
  ip -n "$ns" link set eth0 up
  [ "$h" = rt ] || ip -n "$ns" route add 10.78.0.0/24 via "${addr[rt]}"
done
rt="${prefix}rt"
ip link add "${prefix}s2a" netns "${prefix}s2" type veth peer name s2 netns "$rt"
ip -n "${prefix}s2" link set "${prefix}s2a" name eth0
ip -n "${prefix}s2" addr add "${addr[s2]}/24" dev eth0
ip -n "${prefix}s2" link set eth0 up
ip -n "${prefix}s2" route add default via 10.78.0.1
ip -n "$rt" addr add 10.78.0.1/24 dev s2
ip -n "$rt" link set s2 up
# The router: packets from s2 go out of TUN wan0, packets to s2 from the bridge out of wan1;
# link_emulator.py moves each to the other TUN after the delay, where the main table routes it.
ip netns exec "$rt" sysctl -q -w net.ipv4.ip_forward=1 net.ipv4.conf.all.rp_filter=0 \
  net.ipv4.conf.default.rp_filter=0
for t in wan0 wan1; do
  ip -n "$rt" tuntap add dev "$t" mode tun || skip "cannot create a TUN device"
  ip netns exec "$rt" sysctl -q -w "net.ipv4.conf.$t.rp_filter=0"
  ip -n "$rt" link set "$t" up
done
ip netns exec "$rt" sysctl -q -w net.ipv4.conf.eth0.rp_filter=0 net.ipv4.conf.s2.rp_filter=0
ip -n "$rt" route add default dev wan0 table 100
ip -n "$rt" route add 10.78.0.0/24 dev wan1 table 101
ip -n "$rt" rule add iif s2 lookup 100
ip -n "$rt" rule add iif eth0 to 10.78.0.0/24 lookup 101
log_dir=${MICRODEX_NETNS_LOG_DIR:-/tmp}
ip netns exec "$rt" python3 "$here/link_emulator.py" wan0 wan1 --delay-ms "${MICRODEX_LINK_DELAY_MS:-50}" \
  --loss "${MICRODEX_LINK_LOSS:-0.02}" \
  2>"$log_dir/${prefix}-link.log" &
emulator=$!

# Every host reaches every other (the far one through the slow link; ping may lose one).
for h in ds s1 s2; do
  ok=0
  for _ in 1 2 3 4 5; do
    if ip netns exec "${prefix}in" ping -c 1 -W 1 "${addr[$h]}" >/dev/null; then ok=1; break; fi
  done
  [ $ok -eq 1 ] || { echo "netns_run: ${addr[$h]} unreachable from in" >&2; exit 1; }
done
rtt=$(ip netns exec "${prefix}in" ping -c 3 -i 0.2 "${addr[s2]}" | sed -nE 's/.*= [0-9.]+\/([0-9.]+)\/.*/\1/p')
echo "netns_run: far station round trip ${rtt:-?} ms (two 50 ms hops)"

export MICRODEX_NETNS_PREFIX="$prefix" MICRODEX_NETNS_SWITCH="$sw"
export MICRODEX_NETNS_DS="${prefix}ds" MICRODEX_NETNS_IN="${prefix}in"
export MICRODEX_NETNS_S1="${prefix}s1" MICRODEX_NETNS_S2="${prefix}s2" MICRODEX_NETNS_RT="$rt"
export MICRODEX_ADDR_DS="${addr[ds]}" MICRODEX_ADDR_IN="${addr[in]}"
export MICRODEX_ADDR_S1="${addr[s1]}" MICRODEX_ADDR_S2="${addr[s2]}"
ip netns exec "${prefix}in" "$binary" "$@"
status=$?
kill -TERM "$emulator" 2>/dev/null
wait "$emulator" 2>/dev/null
cat "$log_dir/${prefix}-link.log" >&2
rm -f "$log_dir/${prefix}-link.log"
exit $status
