"""How many vehicles one emulator process holds at real time with 10 Hz telemetry, on one core.

Every vehicle is armed, flying a position setpoint with its detection sensor on, and its
telemetry is drained by a sink process. The emulator is one process with one event-loop thread,
so it can use at most one core. A size fits one core when the process needs less than 0.9
core-seconds of CPU per sim second at speed-up 1 (one core keeps real time with headroom) and
every vehicle delivered >= 9.9 telemetry datagrams per sim second (one per 10 Hz tick). Whether
the sim clock actually kept pace (sim/wall >= 0.98) is printed too: on a shared, oversubscribed
host the process is descheduled and that column measures the host, not the emulator.
Beyond 254 vehicles the MAVLink system ids repeat (vehicle i is system i % 254 + 1), every
vehicle on its own UDP port as always. Usage: python benchmarks/emulator_capacity.py [N ...]
"""

from __future__ import annotations

import sys

from emulator_common import load_note, run

WALL = 10.0


def main() -> None:
    sizes = [int(a) for a in sys.argv[1:]] or [254, 508, 1000, 1500, 2000]
    best = paced = 0
    print(load_note())
    print(
        f"{'vehicles':>8} {'sim/wall':>8} {'cpu/sim-s':>9} {'rebases':>7} {'dgram/sim-s':>11}"
        "  fits-one-core  kept-pace"
    )
    for n in sizes:
        r = run(n, 1.0, WALL, 31000)
        ok = r.cpu_per_sim_s < 0.9 and r.datagrams_per_vehicle_per_sim_s >= 9.9
        kept = ok and r.ratio >= 0.98
        print(
            f"{n:>8} {r.ratio:>8.3f} {r.cpu_per_sim_s:>9.2f} {r.rebases:>7} "
            f"{r.datagrams_per_vehicle_per_sim_s:>11.2f}  {'yes' if ok else 'no':>13}"
            f"  {'yes' if kept else 'no':>9}",
            flush=True,
        )
        best = max(best, n) if ok else best
        paced = max(paced, n) if kept else paced
    print(load_note())
    print(f"vehicles at real time with 10 Hz telemetry within one core's CPU: {best}")
    print(f"largest size whose sim clock kept pace on this host during the run: {paced}")
    print("(system ids repeat every 254 vehicles, each vehicle on its own UDP port)")


if __name__ == "__main__":
    main()
