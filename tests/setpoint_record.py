"""A seeded lockstep fleet mission's setpoints and decisions, to compare a code change against.

Flies 3 vehicles of a small profile (seed 7, 300 sim s, pymavlink, lockstep at 100x) against the
emulator and reads from each vehicle's .tlog and mission log what is deterministic:

- ``waypoints``: the sequence of targets (x, y, z of SET_POSITION_TARGET_LOCAL_NED) in the
  search phase, in the profile's frame (x, y plus the vehicle's local origin from the mission
  log's ``frame`` event: 0 for records made when the emulator's local frame was the profile's),
  each with the search time it was first sent;
- ``velocities``: the horizontal velocity setpoint (vn, ve) at every whole search second;
- ``decisions``: the mission log's detections, confirmations, fall-backs, levels and its end,
  with the search time.

Compared: each vehicle's search up to its first sensor switch (the first detection, which moves
it to the next level). Not after it: the companion switches sensors by PARAM_SET MDM_SENSOR,
which lockstep does not wait for, so at 100x the emulator reads with the old sensor for a few
ticks more or less depending on wall time; on a loaded host (load 13) one vehicle's later
search took another course. Up to the switch the same seed gives the same mission.

Search time is the setpoint's (or record's) vehicle time less the vehicle's search start.
Absolute times are not comparable: before OFFBOARD the emulator's clock runs on at 100x while
the companion starts, arms and climbs, so a run's search starts 15-45 sim s in depending on
wall time, at an altitude a few tenths of a metre apart (so the vertical velocity and the
float32 noise of the horizontal one differ). Within the search the emulator holds its clock
for every setpoint, and the same seed gives the same targets and sensor readings; what still
varies is the millisecond of a timestamp (the emulator's float clock) and, on a loaded host, a
tick a companion answered after the 0.25 wall s lockstep limit (one setpoint missing).
:func:`differences` allows for exactly that.

To make the record (runs the mission twice and refuses to write unless the two agree):

    cd /tmp && PYTHONPATH=/path/to/checkout-of-COMMIT \\
        /path/to/worktree/.venv/bin/python /path/to/worktree/tests/setpoint_record.py \\
        --write /path/to/worktree/tests/data/setpoints-COMMIT.json

(run from outside any checkout: ``python -m companion.cli`` of the fleet's processes imports from
the working directory first). The record names the commit of the code it flew.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

from pymavlink import mavutil

import companion
from companion.telemetry.mission_log import read_records
from mdm_ground.fleet.runner import FleetOptions, run_fleet

PROFILE = """
name: setpoint-record
area: {north: 3000.0, east: 3000.0}
targets:
  - {north: 1500.0, east: 1500.0}
  - {north: 600.0, east: 2400.0, false_target: true}
fleet: {vehicles: 3, speed: 20.0, tau: 0.33, altitude: 30.0, altitude_step: 5.0}
sensors:
  - {name: detection, radius: 1000.0}
  - {name: confirmation, radius: 50.0}
policy:
  kind: mdm
  levels:
    - {distribution: LS, step: 600.0}
    - distribution: BS
      step: 1000.0
      index: {gamma: 0.1, index_max: 0.95, index_min: 0.2, kappa: 150.0}
mission: {duration: 5000.0, ts_cap: 5000.0}
"""
VEHICLES = 3
SEED = 7
DURATION = 300.0
DECISIONS = ("detection", "confirmation", "fallback", "level", "end")
TIME_TOLERANCE = 0.25
"""Search seconds a waypoint or decision may move: the millisecond of a timestamp, rounding, one
missed lockstep tick (0.1 s) on a loaded host."""
WAYPOINT_TOLERANCE = 0.02
"""m: a target in the profile's frame is the float32 on the wire plus the vehicle's origin,
which GPS_GLOBAL_ORIGIN carries in 1e-7 degrees (1.1 cm) and the mission log to the
centimetre (measured: 1.7-4.5 mm on every waypoint, 1.0 cm on the first)."""
VELOCITY_TOLERANCE = 0.01
"""m/s: float32 noise of the same velocity computed from positions a few ms of flight apart."""
MISSING_SAMPLES = 5
"""Whole search seconds of a vehicle that may lack a setpoint in one of the runs (a tick answered
late on a loaded host)."""


def fly(out: Path) -> dict[str, Any]:
    """Fly the mission into the new folder ``out`` and read its record."""
    out.mkdir(parents=True)
    profile = out / "setpoint-record.yaml"
    profile.write_text(PROFILE)
    run_fleet(
        FleetOptions(
            profile=str(profile),
            out=out / "run",
            vehicles=VEHICLES,
            speedup=100.0,
            duration=DURATION,
            seed=SEED,
            land_wait=0.0,
            lockstep=True,
        )
    )
    return {str(v): vehicle_record(out / "run", v) for v in range(VEHICLES)}


def vehicle_record(run: Path, vehicle: int) -> dict[str, Any]:
    """Waypoints, velocity samples and decisions of one vehicle of a finished run."""
    records = read_records(run / f"mission-{vehicle}.jsonl")
    starts = [
        r["search_start"] for r in records if r.get("event") == "phase" and "search_start" in r
    ]
    if not starts:
        raise RuntimeError(f"vehicle {vehicle} of {run} never started its search")
    start = float(starts[0])
    frames = [r for r in records if r.get("event") == "frame"]
    north, east = (float(frames[-1]["north"]), float(frames[-1]["east"])) if frames else (0.0, 0.0)
    waypoints: list[list[float]] = []
    velocities: dict[str, list[float]] = {}
    log = mavutil.mavlink_connection(str(run / f"vehicle-{vehicle}.tlog"), dialect="ardupilotmega")
    while (msg := log.recv_match(type="SET_POSITION_TARGET_LOCAL_NED")) is not None:
        t = msg.time_boot_ms / 1000.0 - start
        if t < -0.0005:
            continue
        target = [msg.x + north, msg.y + east, msg.z]
        if not waypoints or waypoints[-1][1:] != target:
            waypoints.append([round(t, 3), *target])
        tenth = round(t * 10)
        if tenth % 10 == 0:
            velocities[str(tenth // 10)] = [msg.vx, msg.vy]
    decisions = [
        {**{k: v for k, v in r.items() if k != "t"}, "t": round(float(r["t"]) - start, 3)}
        for r in records
        if r.get("event") in DECISIONS and float(r["t"]) >= start
    ]
    return {"waypoints": waypoints, "velocities": velocities, "decisions": decisions}


def differences(before: dict[str, Any], after: dict[str, Any]) -> list[str]:
    """What ``after`` does differently from ``before`` (empty: the same mission)."""
    out: list[str] = []
    for vehicle in sorted(set(before) | set(after)):
        if vehicle not in before or vehicle not in after:
            out.append(f"vehicle {vehicle} in only one of the runs")
            continue
        b, a = before[vehicle], after[vehicle]
        first = [d["t"] for d in b["decisions"] if d["event"] == "level" and d["level"] != 0]
        end = (first[0] if first else math.inf) + TIME_TOLERANCE
        out += [
            f"vehicle {vehicle}: {d}" for d in _vehicle_differences(_upto(b, end), _upto(a, end))
        ]
    return out


def _upto(vehicle: dict[str, Any], end: float) -> dict[str, Any]:
    """The part of a vehicle's record up to search time ``end``."""
    return {
        "waypoints": [w for w in vehicle["waypoints"] if w[0] <= end],
        "velocities": {s: v for s, v in vehicle["velocities"].items() if int(s) <= end},
        "decisions": [d for d in vehicle["decisions"] if d["t"] <= end],
    }


def _vehicle_differences(b: dict[str, Any], a: dict[str, Any]) -> list[str]:
    out: list[str] = []
    if not _same_targets(b["waypoints"], a["waypoints"]):
        out.append(f"waypoints {b['waypoints']} became {a['waypoints']}")
    else:
        out += [
            f"waypoint {wb[1:]} sent at {wa[0]} s, was {wb[0]} s"
            for wb, wa in zip(b["waypoints"], a["waypoints"], strict=True)
            if abs(wb[0] - wa[0]) > TIME_TOLERANCE
        ]
    untimed = [{k: v for k, v in d.items() if k != "t"} for d in b["decisions"]]
    if untimed != [{k: v for k, v in d.items() if k != "t"} for d in a["decisions"]]:
        out.append(f"decisions {b['decisions']} became {a['decisions']}")
    else:
        out += [
            f"{da} at {da['t']} s, was {db['t']} s"
            for db, da in zip(b["decisions"], a["decisions"], strict=True)
            if abs(db["t"] - da["t"]) > TIME_TOLERANCE
        ]
    vb, va = b["velocities"], a["velocities"]
    if len(set(vb) ^ set(va)) > MISSING_SAMPLES:
        out.append(f"velocity samples at {sorted(set(vb) ^ set(va), key=int)} s in one run only")
    out += [
        f"velocity at {s} s: {va[s]}, was {vb[s]}"
        for s in sorted(set(vb) & set(va), key=int)
        if not _close(vb[s], va[s])
    ]
    return out


def _same_targets(before: list[list[float]], after: list[list[float]]) -> bool:
    return len(before) == len(after) and all(
        math.isclose(x, y, abs_tol=WAYPOINT_TOLERANCE)
        for wb, wa in zip(before, after, strict=True)
        for x, y in zip(wb[1:], wa[1:], strict=True)
    )


def _close(before: list[float], after: list[float]) -> bool:
    return all(
        math.isclose(b, a, abs_tol=VELOCITY_TOLERANCE) for b, a in zip(before, after, strict=True)
    )


def code_commit() -> str:
    """The commit of the checkout the ``companion`` package was imported from (+ if edited)."""
    where = Path(companion.__file__).resolve().parent.parent
    head = subprocess.run(
        ["git", "-C", str(where), "rev-parse", "--short", "HEAD"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    dirty = subprocess.run(["git", "-C", str(where), "status", "--porcelain", "--", "companion",
                            "mdm_core", "sim_vehicle_stub", "mdm_profiles"],
                           capture_output=True, text=True, check=True).stdout.strip()  # fmt: skip
    return head + ("+" if dirty else "")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--write", type=Path, required=True, help="the record file to write")
    args = p.parse_args()
    commit = code_commit()
    print(f"flying the code of {commit} ({Path(companion.__file__).parent})", file=sys.stderr)
    with tempfile.TemporaryDirectory() as tmp:
        first, second = fly(Path(tmp) / "first"), fly(Path(tmp) / "second")
    if found := differences(first, second):
        raise SystemExit("two runs at the same seed differ:\n" + "\n".join(found))
    record = {"commit": commit, "made_by": "tests/setpoint_record.py", "vehicles": first}
    args.write.write_text(json.dumps(record, indent=1) + "\n")
    print(f"wrote {args.write}", file=sys.stderr)


if __name__ == "__main__":
    main()
