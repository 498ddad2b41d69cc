#!/usr/bin/env bash
# A station + instructor run on the loopback profile sends nothing off the host.
# Usage: loopback_only_test.sh BIN_DIR DOMAIN
#
# Two checks:
#  1. tcpdump on every non-loopback interface that is up, filtering on the run's RTPS ports
#     (domain D: 7400 + 250 D ... + 249) and on RTPS multicast (239.255.0.1): no packet may
#     be captured. Used when tcpdump can capture here (root or CAP_NET_RAW); otherwise the
#     test says so and relies on check 2.
#  2. Every UDP/TCP socket the processes hold is bound to 127.0.0.1 (from /proc/PID/fd and
#     /proc/net/{udp,tcp}), so the kernel cannot route their traffic to another interface.
set -euo pipefail
bin="$1"
domain="$2"
scene="$(pwd)/assets/scenes/needle_tube.yaml"
work="$(mktemp -d)"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT

lo_port=$((7400 + 250 * domain))
hi_port=$((lo_port + 249))
filter="(udp or tcp) and (portrange ${lo_port}-${hi_port} or dst host 239.255.0.1)"
ifaces=$(ip -o link show up | awk -F': ' '{print $2}' | sed 's/@.*//' | grep -v '^lo$' || true)

captures=()
capture_ok=0
for i in $ifaces; do
  if timeout 2 tcpdump -i "$i" -c 1 -w /dev/null 'udp port 1' >/dev/null 2>"$work/probe.$i"; then :; fi
  if grep -q "listening on" "$work/probe.$i"; then
    tcpdump -i "$i" -n -U -w "$work/cap.$i.pcap" "$filter" 2>"$work/tcpdump.$i.log" &
    pids+=($!)
    captures+=("$i")
  fi
done
# Wait until every capture is listening.
for i in "${captures[@]}"; do
  for _ in $(seq 50); do grep -q "listening on" "$work/tcpdump.$i.log" && break; sleep 0.1; done
  grep -q "listening on" "$work/tcpdump.$i.log" && capture_ok=1
done

"$bin/microdex-station" --scene "$scene" --station-id lo-1 --domain "$domain" --duration 5 \
  --score-out "$work/lo-1.json" >"$work/st1.log" 2>&1 &
st1=$!
pids+=($st1)
"$bin/microdex-station" --scene "$scene" --station-id lo-2 --domain "$domain" --duration 5 \
  >"$work/st2.log" 2>&1 &
st2=$!
pids+=($st2)
"$bin/microdex-instructor" --headless --domain "$domain" --duration 4 --table-period 0 \
  --cue all:tremor:2@1 >"$work/instr.log" 2>&1 &
instr=$!
pids+=($instr)
sleep 2

# Check 2: sockets of the three processes.
bad=0
nsock=0
for p in $st1 $st2 $instr; do
  for fd in /proc/$p/fd/*; do
    link=$(readlink "$fd" 2>/dev/null || true)
    [[ "$link" =~ ^socket:\[([0-9]+)\]$ ]] || continue
    inode="${BASH_REMATCH[1]}"
    line=$(awk -v ino="$inode" 'NR > 1 && $10 == ino {print $2}' /proc/net/udp /proc/net/tcp)
    [ -z "$line" ] && continue  # a unix socket (SHM transport signalling) or netlink
    nsock=$((nsock + 1))
    addr="${line%%:*}"
    if [ "$addr" != "0100007F" ]; then
      echo "process $p: socket inode $inode bound to $line (not 127.0.0.1)"
      bad=1
    fi
  done
done
echo "socket check: $nsock IP sockets of station+station+instructor, all on 127.0.0.1: $([ $bad = 0 ] && echo yes || echo NO)"

wait $instr || { echo "instructor failed"; cat "$work/instr.log"; exit 1; }
wait $st1 || { echo "station failed"; cat "$work/st1.log"; exit 1; }
wait $st2 || { echo "station failed"; cat "$work/st2.log"; exit 1; }
grep -q '"cues_applied": \[{' "$work/lo-1.json" || { echo "the run did not exchange a cue"; exit 1; }
grep -q "score lo-1" "$work/instr.log" || { echo "the instructor saw no score"; cat "$work/instr.log"; exit 1; }

packets=0
if [ ${#captures[@]} -gt 0 ] && [ $capture_ok = 1 ]; then
  sleep 0.5
  for i in "${captures[@]}"; do
    n=$(tcpdump -r "$work/cap.$i.pcap" -n 2>/dev/null | wc -l)
    echo "tcpdump on $i: $n packets of the run's RTPS ports or RTPS multicast"
    packets=$((packets + n))
  done
else
  echo "tcpdump cannot capture here (no usable non-loopback interface or no permission): socket check only"
fi
[ $bad = 0 ] || exit 1
[ $packets = 0 ] || exit 1
echo "loopback only: ok"
