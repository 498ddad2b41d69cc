#!/usr/bin/env python3
"""A slow, lossy link between two TUN devices: what `tc qdisc ... netem delay D loss P` does,
for kernels built without sch_netem.

Every IP packet the kernel routes out of TUN A is written into TUN B (the kernel then receives
it there and forwards it on), and B's into A, each after a fixed delay, and each dropped with
probability P (a seeded generator: a run is repeatable). One direction's packets keep their
order. On SIGTERM it prints what it forwarded and dropped on stderr and exits.

Usage: link_emulator.py TUN_A TUN_B --delay-ms 50 --loss 0.02 [--seed 1]
The TUN devices must exist (ip tuntap add dev NAME mode tun) in the calling namespace.
"""
import argparse
import collections
import fcntl
import os
import random
import select
import signal
import struct
import sys
import time

TUNSETIFF = 0x400454CA
IFF_TUN = 0x0001
IFF_NO_PI = 0x1000


def open_tun(name):
    fd = os.open("/dev/net/tun", os.O_RDWR)
    fcntl.ioctl(fd, TUNSETIFF, struct.pack("16sH", name.encode(), IFF_TUN | IFF_NO_PI))
    os.set_blocking(fd, False)
    return fd


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("tun_a")
    parser.add_argument("tun_b")
    parser.add_argument("--delay-ms", type=float, default=50.0)
    parser.add_argument("--loss", type=float, default=0.02)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    if not (0 <= args.loss < 1 and args.delay_ms >= 0):
        parser.error("--loss: expected 0..1 (exclusive), --delay-ms: expected >= 0")
    rng = random.Random(args.seed)
    delay_s = args.delay_ms * 1e-3
    fd_a, fd_b = open_tun(args.tun_a), open_tun(args.tun_b)
    peer = {fd_a: fd_b, fd_b: fd_a}
    queue = {fd_a: collections.deque(), fd_b: collections.deque()}  # to write: (due, packet)
    stats = {"forwarded": 0, "dropped": 0, "write_failed": 0}
    running = [True]

    def stop(*_):
        running[0] = False

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    poller = select.poll()
    poller.register(fd_a, select.POLLIN)
    poller.register(fd_b, select.POLLIN)
    while running[0]:
        now = time.monotonic()
        due = [q[0][0] for q in queue.values() if q]
        timeout_ms = max(0.0, (min(due) - now) * 1e3) if due else 100.0
        try:
            events = poller.poll(timeout_ms)
        except InterruptedError:
            continue
        now = time.monotonic()
        for fd, _ in events:
            for _ in range(256):
                try:
                    packet = os.read(fd, 65536)
                except BlockingIOError:
                    break
                if rng.random() < args.loss:
                    stats["dropped"] += 1
                else:
                    queue[peer[fd]].append((now + delay_s, packet))
        now = time.monotonic()
        for fd, q in queue.items():
            while q and q[0][0] <= now:
                _, packet = q.popleft()
                try:
                    os.write(fd, packet)
                    stats["forwarded"] += 1
                except OSError:
                    stats["write_failed"] += 1
    total = stats["forwarded"] + stats["dropped"]
    print("link_emulator: %d packets, %d forwarded after %.0f ms, %d dropped (%.2f %%), "
          "%d write failures" % (total, stats["forwarded"], args.delay_ms, stats["dropped"],
                                 100.0 * stats["dropped"] / max(total, 1), stats["write_failed"]),
          file=sys.stderr)


if __name__ == "__main__":
    main()
