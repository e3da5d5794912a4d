"""How fast this host is right now, for comparing figures taken on different days.

    .venv/bin/python benchmarks/host_speed.py [--rounds 3]

The shared virtual machines these benchmarks run on differ from day to day by 2x and more, and
within an hour; a figure of another benchmark says little without this beside it. Printed per
round: the wall time of a pure-Python loop of 10^7 additions (the interpreter's speed), and a
UDP ping-pong on 127.0.0.1 between two processes (the fleet's pattern: each answer wakes the
other process): the wall time of a round trip and the CPU time each side spends per datagram
it receives and sends back. The second figure is the lockstep fleet's floor per answer: no
process that answers over UDP can spend less.
"""

from __future__ import annotations

import argparse
import os
import socket
import time

_ROUND_TRIPS = 20_000


def python_loop_s() -> float:
    """Wall seconds of 10^7 integer additions in a Python loop."""
    start = time.perf_counter()
    total = 0
    for i in range(10**7):
        total += i
    return time.perf_counter() - start


def ping_pong() -> tuple[float, float, float]:
    """(wall us per round trip, CPU us of the sender per trip, CPU us of the echoing child)."""
    here = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    there = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    here.bind(("127.0.0.1", 0))
    there.bind(("127.0.0.1", 0))
    child = os.fork()
    if child == 0:  # the echo: a blocking receive, one send back
        for _ in range(_ROUND_TRIPS):
            data, source = there.recvfrom(2048)
            there.sendto(data, source)
        os._exit(0)
    address, payload = there.getsockname(), b"x" * 60
    before, start = os.times(), time.perf_counter()
    for _ in range(_ROUND_TRIPS):
        here.sendto(payload, address)
        here.recvfrom(2048)
    wall = time.perf_counter() - start
    after = os.times()
    os.waitpid(child, 0)
    ended = os.times()
    here.close()
    there.close()
    own = after.user + after.system - (before.user + before.system)
    echo = ended.children_user + ended.children_system
    echo -= before.children_user + before.children_system
    scale = 1e6 / _ROUND_TRIPS
    return wall * scale, own * scale, echo * scale


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(f"{'round':>5} {'loop 1e7 s':>11} {'UDP round trip us':>18} {'CPU us sender':>14} "
          f"{'CPU us echo':>12}")  # fmt: skip
    for k in range(1, args.rounds + 1):
        loop = python_loop_s()
        wall, own, echo = ping_pong()
        print(f"{k:>5} {loop:>11.2f} {wall:>18.1f} {own:>14.1f} {echo:>12.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
