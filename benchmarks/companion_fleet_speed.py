"""Sim-time / wall-time ratio of a 12-vehicle live fleet, CPU per sim second, and latency.

    .venv/bin/python benchmarks/companion_fleet_speed.py --speedup 100 --duration 600

Ratio: sim seconds / wall seconds between the first and the last 'tick' record (10 sim s
apart, with the wall clock) of vehicles in the search phase. CPU: user + system seconds of the
emulator and of every companion process (read from /proc every 0.25 s, Linux), over the same
search window, per sim second: the fleet cannot run faster than (cores / total) however the
work is scheduled, nor faster than 1 / emulator (one process, one core). That window also
holds companions starting (imports: seconds of CPU each) and companions that ended their search
drawing their map (matplotlib: 1-3 CPU s each) while others still search, so
``cpu_s_per_sim_s_companion_own_search_mean`` takes each companion over its own search only
(its first to its last search tick) per sim s of it, and ``cpu_us_per_answer_own_search`` is
that per setpoint (10 per sim s): what answering costs (benchmarks/companion_answer_cost.py
gives the same without the fleet's contention). Latency: from the
arrival of a LOCAL_POSITION_NED datagram to the setpoint leaving the socket, per vehicle (p50,
p99 of each vehicle's mission; the summary gives the median p50 and the worst p99). Setpoint
rate: SET_POSITION_TARGET_LOCAL_NED per vehicle second during the search (from each .tlog; a
setpoint carries the time_boot_ms of the position it answers), the lowest over vehicles, and
the longest gap.
"""

from __future__ import annotations

import argparse
import json
import os
import threading
import time
from pathlib import Path

import numpy as np
from code_commit import commit_of
from pymavlink import mavutil

import companion
from companion.telemetry.mission_log import read_records
from mdm_ground.fleet.runner import FleetOptions, run_fleet

_TICK = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100


class CpuSampler:
    """CPU seconds of this process's children over time, labelled emulator / companion."""

    def __init__(self, every: float = 0.25) -> None:
        self.every = every
        self.samples: list[tuple[float, dict[int, tuple[str, float]]]] = []
        self.vehicle: dict[int, int] = {}
        """Companion pid -> vehicle index."""
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> CpuSampler:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()

    def _run(self) -> None:
        me = os.getpid()
        roles: dict[int, str] = {}
        while not self._stop.is_set():
            now, seen = time.time(), {}
            for entry in os.listdir("/proc") if os.path.isdir("/proc") else []:
                if not entry.isdigit():
                    continue
                try:
                    stat = Path(f"/proc/{entry}/stat").read_text()
                    fields = stat[stat.rindex(")") + 2 :].split()
                    if int(fields[1]) != me:
                        continue
                    pid = int(entry)
                    if pid not in roles:
                        cmd = Path(f"/proc/{entry}/cmdline").read_bytes().split(b"\0")
                        roles[pid] = "emulator" if b"sim_vehicle_stub.cli" in cmd else "companion"
                        if b"--vehicle" in cmd:
                            self.vehicle[pid] = int(cmd[cmd.index(b"--vehicle") + 1])
                    seen[pid] = (roles[pid], (int(fields[11]) + int(fields[12])) / _TICK)
                except (OSError, ValueError, IndexError):
                    continue
            self.samples.append((now, seen))
            self._stop.wait(self.every)

    def per_role(self, w0: float, w1: float) -> dict[str, list[float]]:
        """CPU seconds each process spent between wall times w0 and w1 (a process that ended
        before w1 counts up to its last sample)."""
        first: dict[int, float] = {}
        last: dict[int, tuple[str, float]] = {}
        for wall, seen in self.samples:
            if wall < w0 - self.every or wall > w1 + self.every:
                continue
            for pid, (role, cpu) in seen.items():
                first.setdefault(pid, cpu)
                last[pid] = (role, cpu)
        out: dict[str, list[float]] = {}
        for pid, (role, cpu) in last.items():
            out.setdefault(role, []).append(cpu - first[pid])
        return out

    def of_vehicle(self, vehicle: int, w0: float, w1: float) -> float | None:
        """CPU seconds of vehicle ``vehicle``'s companion between the first sample at or after
        wall time w0 and the last at or before w1 (None without two such samples)."""
        pids = [pid for pid, v in self.vehicle.items() if v == vehicle]
        inside = [
            (wall, seen[pid][1])
            for wall, seen in self.samples
            for pid in pids
            if pid in seen and w0 <= wall <= w1
        ]
        return inside[-1][1] - inside[0][1] if len(inside) > 1 else None


def setpoint_rate(tlog: Path, search_start: float) -> tuple[float, float]:
    """Setpoints per vehicle second after ``search_start`` and the longest gap (vehicle s)."""
    log = mavutil.mavlink_connection(str(tlog), dialect="ardupilotmega")
    times = []
    while (msg := log.recv_match(type="SET_POSITION_TARGET_LOCAL_NED")) is not None:
        if msg.time_boot_ms / 1000.0 >= search_start:
            times.append(msg.time_boot_ms / 1000.0)
    t = np.array(times)
    if len(t) < 2:
        return float("nan"), float("nan")
    return float((len(t) - 1) / np.ptp(t)), float(np.diff(t).max())


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--profile", default="paper-fixed")
    p.add_argument("--vehicles", type=int, default=12)
    p.add_argument("--speedup", type=float, default=100.0)
    p.add_argument("--duration", type=float, default=600.0)
    p.add_argument("--backend", default="pymavlink")
    p.add_argument(
        "--lockstep",
        action="store_true",
        help="FleetOptions(lockstep=True): the emulator waits for every setpoint",
    )
    p.add_argument("--base-port", type=int, default=37540)
    p.add_argument(
        "--out",
        type=Path,
        default=Path("runs/bench-fleet"),
        help="a new run directory is made under it for every run",
    )
    args = p.parse_args()
    # A fresh directory: companions finding an ended mission log would not fly again.
    args.out = args.out / time.strftime("%Y%m%d-%H%M%S")
    started = time.perf_counter()
    with CpuSampler() as cpu:
        result = run_fleet(FleetOptions(profile=args.profile, out=args.out, vehicles=args.vehicles,
                                        speedup=args.speedup, duration=args.duration,
                                        backend=args.backend, base_port=args.base_port,
                                        # (only when asked: runs on commits without it too)
                                        **({"lockstep": True} if args.lockstep else {})))  # type: ignore[arg-type]  # fmt: skip
    wall_total = time.perf_counter() - started
    ticks, p50, p99, rates, own = [], [], [], [], []
    for i in range(args.vehicles):
        mine = []
        for r in read_records(args.out / f"mission-{i}.jsonl"):
            if r.get("event") == "phase" and "search_start" in r:
                rates.append(setpoint_rate(args.out / f"vehicle-{i}.tlog", r["search_start"]))
            if r.get("event") == "tick" and r.get("phase") == "search" and "wall" in r:
                mine.append((float(r["t"]), float(r["wall"])))
            elif r.get("event") == "latency":
                p50.append(float(r["p50_ms"]))
                p99.append(float(r["p99_ms"]))
        ticks += mine
        if len(mine) > 1:
            # this companion's CPU over its own search only (not its start-up, nor its map
            # drawn after its search while others still search), per sim s of it
            (t0, w0), (t1, w1) = mine[0], mine[-1]
            spent = cpu.of_vehicle(i, w0, w1)
            if spent is not None and t1 > t0:
                own.append(spent / (t1 - t0))
    sim = np.array(ticks)
    ratio = float(np.ptp(sim[:, 0]) / np.ptp(sim[:, 1])) if len(sim) > 1 else float("nan")
    usage: dict[str, object] = {}
    if len(sim) > 1:
        # search window: sim time runs alike for every vehicle (one emulator clock)
        w0, w1 = float(sim[:, 1].min()), float(sim[:, 1].max())
        roles = cpu.per_role(w0, w1)
        per_sim = float(np.ptp(sim[:, 0]))
        emu = sum(roles.get("emulator", [])) / per_sim
        comps = np.array(roles.get("companion", [])) / per_sim
        total = emu + float(comps.sum())
        usage = {
            "cpu_s_per_sim_s_emulator": round(emu, 5),
            "cpu_s_per_sim_s_companion_mean": round(float(comps.mean()), 5) if len(comps) else None,
            "cpu_s_per_sim_s_companion_own_search_mean": round(float(np.mean(own)), 5)
            if own
            else None,
            "cpu_us_per_answer_own_search": round(float(np.mean(own)) * 1e5, 1) if own else None,
            "cpu_s_per_sim_s_total": round(total, 5),
            "bound_2_cores": round(2.0 / total, 1) if total > 0 else None,
            "bound_emulator_core": round(1.0 / emu, 1) if emu > 0 else None,
        }
    out = {
        "code": commit_of(Path(companion.__file__).resolve().parent.parent),
        "vehicles": args.vehicles,
        "backend": args.backend,
        "speedup_requested": args.speedup,
        "lockstep": args.lockstep or args.speedup <= 0,
        "sim_wall_ratio_search": round(ratio, 1),
        "wall_total_s": round(wall_total, 1),
        **usage,
        "latency_p50_ms_median": round(float(np.median(p50)), 3) if p50 else None,
        "latency_p99_ms_worst": round(float(np.max(p99)), 3) if p99 else None,
        "setpoints_per_sim_s_min": round(min(r for r, _ in rates), 2) if rates else None,
        "setpoint_gap_max_sim_s": round(max(g for _, g in rates), 2) if rates else None,
        "load_average_1min": round(os.getloadavg()[0], 2),
        "tnc": result.tnc,
        "false_confirmations": result.false_confirmations,
    }
    print(json.dumps(out))


if __name__ == "__main__":
    main()
