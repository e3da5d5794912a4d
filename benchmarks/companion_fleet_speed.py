"""Sim-time / wall-time ratio of a 12-vehicle live fleet and the decision-to-setpoint latency.

    .venv/bin/python benchmarks/companion_fleet_speed.py --speedup 100 --duration 600

Ratio: sim seconds / wall seconds between the first and the last 'tick' record (10 sim s
apart, with the wall clock) of vehicles in the search phase. Latency: from the arrival of a
LOCAL_POSITION_NED datagram to the setpoint leaving the socket, per vehicle (p50, p99 of each
vehicle's mission; the summary gives the median p50 and the worst p99 over vehicles).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from companion.fleet.runner import FleetOptions, run_fleet
from companion.telemetry.mission_log import read_records


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--profile", default="paper-fixed")
    p.add_argument("--vehicles", type=int, default=12)
    p.add_argument("--speedup", type=float, default=100.0)
    p.add_argument("--duration", type=float, default=600.0)
    p.add_argument("--backend", default="pymavlink")
    p.add_argument("--base-port", type=int, default=37540)
    p.add_argument("--out", type=Path, default=Path("runs/bench-fleet"))
    args = p.parse_args()
    started = time.perf_counter()
    result = run_fleet(FleetOptions(profile=args.profile, out=args.out, vehicles=args.vehicles,
                                    speedup=args.speedup, duration=args.duration,
                                    backend=args.backend, base_port=args.base_port))  # fmt: skip
    wall_total = time.perf_counter() - started
    ticks, p50, p99 = [], [], []
    for i in range(args.vehicles):
        for r in read_records(args.out / f"mission-{i}.jsonl"):
            if r.get("event") == "tick" and r.get("phase") == "search" and "wall" in r:
                ticks.append((float(r["t"]), float(r["wall"])))
            elif r.get("event") == "latency":
                p50.append(float(r["p50_ms"]))
                p99.append(float(r["p99_ms"]))
    sim = np.array(ticks)
    ratio = float(np.ptp(sim[:, 0]) / np.ptp(sim[:, 1])) if len(sim) > 1 else float("nan")
    out = {
        "vehicles": args.vehicles, "backend": args.backend, "speedup_requested": args.speedup,
        "sim_wall_ratio_search": round(ratio, 1), "wall_total_s": round(wall_total, 1),
        "latency_p50_ms_median": round(float(np.median(p50)), 3) if p50 else None,
        "latency_p99_ms_worst": round(float(np.max(p99)), 3) if p99 else None,
        "tnc": result.tnc, "false_confirmations": result.false_confirmations,
    }  # fmt: skip
    print(json.dumps(out))


if __name__ == "__main__":
    main()
