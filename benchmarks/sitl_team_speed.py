"""N ArduCopter SITL instances with their companions on this machine (`companion fleet --sitl
arducopter`): for each N, the speed-ups asked in turn, the setpoint rate each vehicle got in its
own time (the SET_POSITION_TARGET_LOCAL_NED a companion sent, from its .tlog, stamped with the
vehicle's time_boot_ms) and the CPU the instances and companions took. A speed-up "keeps 10 Hz"
when every vehicle's setpoints came at >= 9.5 Hz of vehicle time with no gap over 0.3 vehicle s
while it streamed; the first speed-up that does not ends that N's row.

    .venv/bin/python benchmarks/sitl_team_speed.py --vehicles 2 4 8 --speedups 1 2 4 8
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil

from mdm_profiles import load_profile

_STREAM_GAP_S = 2.0
"""A pause longer than this (vehicle s) between two setpoints ends a streaming stretch (take-off,
RTL): such pauses are phases without setpoints, not a slow companion."""


def setpoint_times(tlog: Path) -> list[float]:
    """time_boot_ms (s) of every setpoint the companion sent, in order."""
    f = mavutil.mavlink_connection(str(tlog), notimestamps=False)
    out = []
    while (msg := f.recv_match(type="SET_POSITION_TARGET_LOCAL_NED")) is not None:
        out.append(msg.time_boot_ms / 1000.0)
    return out


def rate(times: list[float]) -> tuple[float, float, float]:
    """(setpoints per vehicle s while streaming, the longest gap in a stretch, streamed s)."""
    count, span, worst = 0, 0.0, 0.0
    for a, b in itertools.pairwise(times):
        gap = b - a
        if gap <= 0 or gap > _STREAM_GAP_S:
            continue
        count += 1
        span += gap
        worst = max(worst, gap)
    return (count / span if span else 0.0), worst, span


def team_profile(folder: Path, vehicles: int) -> Path:
    """field-duebendorf for ``vehicles`` (layers 40 m up in 5 m steps: 75 m for 8, under
    ArduCopter's FENCE_ALT_MAX of 100 m)."""
    p = load_profile("field-duebendorf").model_dump(mode="json", exclude_none=True)
    p["fleet"]["vehicles"] = vehicles
    path = folder / f"field-duebendorf-{vehicles}.yaml"
    path.write_text(json.dumps(p))  # JSON is YAML
    return path


def one_run(n: int, speedup: float, duration: float, folder: Path) -> dict[str, object]:
    out = folder / f"n{n}-x{speedup:g}"
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "companion.cli", "fleet", "--profile", str(team_profile(folder, n)),
         "--sitl", "arducopter", "--vehicles", str(n), "--sitl-speedup", f"{speedup:g}",
         "--sensor-source", "virtual", "--duration", f"{duration:g}", "--out", str(out),
         "--quiet", "--json"],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    rates = [rate(setpoint_times(out / f"vehicle-{i}.tlog")) for i in range(n)]
    try:
        result = json.loads(proc.stdout.splitlines()[-1])
        complete, sim = bool(result["complete"]), float(result["sim_time"])
    except (IndexError, ValueError, KeyError):
        complete, sim = False, 0.0
    kept = complete and all(r >= 9.5 and worst <= 0.3 for r, worst, _ in rates)
    return {
        "n": n,
        "speedup": speedup,
        "wall": wall,
        "cpu": cpu,
        "rates": rates,
        "sim": sim,
        "complete": complete,
        "kept": kept,
        "exit": proc.returncode,
        "out": str(out),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--vehicles", type=int, nargs="+", default=[2, 4, 8])
    parser.add_argument("--speedups", type=float, nargs="+", default=[1.0, 2.0, 4.0, 8.0])
    parser.add_argument("--duration", type=float, default=60.0, help="search time, vehicle s")
    parser.add_argument("--out", type=Path, help="where the runs go (default: a temp dir)")
    args = parser.parse_args()
    folder = args.out or Path(tempfile.mkdtemp(prefix="sitl-team-speed-"))
    folder.mkdir(parents=True, exist_ok=True)
    print(f"load before: {os.getloadavg()[0]:.1f} (1 min); runs in {folder}")
    print(
        "  N  speed-up  wall s  sim s/wall s  CPU s  CPU s/vehicle  cores/vehicle  min Hz  worst gap s  "
        "complete  10 Hz kept"
    )
    for n in args.vehicles:
        for speedup in sorted(args.speedups):
            r = one_run(n, speedup, args.duration, folder)
            rates = r["rates"]
            assert isinstance(rates, list)
            low = min(x[0] for x in rates)
            worst = max(x[1] for x in rates)
            wall, cpu = float(r["wall"]), float(r["cpu"])  # type: ignore[arg-type]
            got = float(r["sim"]) / wall  # type: ignore[arg-type]
            print(f"{n:3d}  {speedup:8g}  {wall:6.0f}  {got:12.1f}  {cpu:5.0f}  {cpu / n:13.1f}  "
                  f"{cpu / n / wall:13.2f}  {low:6.1f}  {worst:11.2f}  {r['complete']!s:>8}  "
                  f"{r['kept']!s:>10}   (load {os.getloadavg()[0]:.1f})", flush=True)  # fmt: skip
            if not r["kept"]:
                break


if __name__ == "__main__":
    main()
