"""The highest speed-up one emulator process sustains with 12 vehicles (10 Hz telemetry per sim
second, everything flying with sensors on, telemetry drained by a sink process).

First flat out (``--speedup max``): sim seconds per wall second, and per CPU second (what one
dedicated core gives; the host is shared). Then the same fleet paced at each requested speed-up:
it is sustained when sim/wall stays >= 0.98 of the target with no clock re-base and every vehicle
delivered >= 9.9 telemetry datagrams per sim second.
Usage: python benchmarks/emulator_speedup.py [SPEEDUP ...]
"""

from __future__ import annotations

import sys

from emulator_common import load_note, run

N = 12
WALL = 8.0


def main() -> None:
    targets = [float(a) for a in sys.argv[1:]] or [50.0, 100.0, 150.0, 200.0]
    print(load_note())
    flat = run(N, None, WALL, 32000)
    print(
        f"flat out, {N} vehicles: sim/wall {flat.ratio:.0f}x, sim/cpu-s "
        f"{flat.sim / flat.cpu:.0f}x (cpu share {flat.cpu_share:.0%}), "
        f"{flat.datagrams_per_vehicle_per_sim_s:.2f} datagrams per vehicle per sim s",
        flush=True,
    )
    best = 0.0
    print(
        f"{'speedup':>8} {'sim/wall':>9} {'rebases':>7} {'cpu':>5} {'dgram/sim-s':>11}  sustained"
    )
    for x in targets:
        r = run(N, x, WALL, 32000)
        ok = r.ratio >= 0.98 * x and r.rebases == 0 and r.datagrams_per_vehicle_per_sim_s >= 9.9
        print(
            f"{x:>8.0f} {r.ratio:>9.1f} {r.rebases:>7} {r.cpu_share:>5.0%} "
            f"{r.datagrams_per_vehicle_per_sim_s:>11.2f}  {'yes' if ok else 'no'}",
            flush=True,
        )
        best = max(best, x) if ok else best
    print(load_note())
    print(f"highest sustained speed-up with {N} vehicles: {best:.0f}x")


if __name__ == "__main__":
    main()
