"""CPU of one companion per position answered, without the emulator and the rest of the fleet.

    .venv/bin/python benchmarks/companion_answer_cost.py --answers 5000

The companion's own code (PymavlinkLink + VehicleMission in the search phase of paper-fixed,
vehicle 0, over real UDP on 127.0.0.1) answers a stand-in vehicle: a child process that sends
what the emulator sends each telemetry tick (LOCAL_POSITION_NED and NAMED_VALUE_FLOAT in one
datagram, HEARTBEAT and SYS_STATUS every tenth tick) and waits for the setpoint before the next
tick, as lockstep does (the first tick's position is where the search starts). Printed: the companion's CPU seconds (user + system of this process,
the vehicle's are not counted) per answer, and the wall time per answer. ``--profile FILE``
also writes a cProfile of the answering (CPU time) for ``python -m pstats``.

Unlike companion_fleet_speed.py this holds no emulator, no other process and no start-up: the
figure is the floor of what one companion costs per answer on this machine, the fleet's
``cpu_s_per_sim_s_companion_mean`` / 10 (answers per sim s) is what it costs in a fleet.
"""

from __future__ import annotations

import argparse
import asyncio
import cProfile
import json
import os
import socket
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from companion.link.pymavlink_link import PymavlinkLink
from companion.mission import MissionConfig, VehicleMission
from companion.mission.control import enter
from companion.mission.phase import Phase
from companion.telemetry.mission_log import MissionLog
from mdm_profiles import load_profile

VEHICLE = """
import socket, sys
from pymavlink.dialects.v20 import ardupilotmega as mavlink2
port, answers = int(sys.argv[1]), int(sys.argv[2])
mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
sock.settimeout(5.0)
for k in range(answers):
    t = 100 * k
    frames = [mav.local_position_ned_encode(t, 500.0 + 2.0 * k, 800.0, -30.0, 20.0, 0.0, 0.0),
              mav.named_value_float_encode(t, b"SENS_SIG", 0.01)]
    if k % 10 == 0:
        frames.append(mav.heartbeat_encode(2, 12, 217, 393216, 4, 3))
        frames.append(mav.sys_status_encode(1, 1, 1, 100, 1, 500, 90, 0, 0, 0, 0, 0, 0))
    sock.sendto(b"".join(bytes(f.pack(mav)) for f in frames), ("127.0.0.1", port))
    while True:  # the setpoint of this tick (the companion's heartbeats pass by)
        data = sock.recv(2048)
        if data[7] == 84:  # SET_POSITION_TARGET_LOCAL_NED
            break
"""


async def answer(answers: int, out: Path, profile: cProfile.Profile | None) -> tuple[float, float]:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    link = PymavlinkLink(url=f"udpin:127.0.0.1:{port}", target_system=1, tlog=out / "v.tlog")
    config = MissionConfig(vehicle=0, profile=load_profile("paper-fixed"), log_dir=out)
    mission = VehicleMission(config, link, MissionLog(out / "mission.jsonl"))
    await link.open()
    vehicle = subprocess.Popen([sys.executable, "-c", VEHICLE, str(port), str(answers)])
    # the first position starts the search there, as the lifecycle does once climbed
    while mission.seen.position is None:
        event = await link.events.get()
        mission.intake.handle_queued(event, link.events)
    _begin_search(mission)
    mission.intake.handle(mission.seen.position)  # the first answer: the vehicle waits for it
    decide = asyncio.create_task(mission.intake.decide())
    cpu, wall = time.process_time(), time.perf_counter()
    if profile is not None:
        profile.enable()
    while vehicle.poll() is None:
        await asyncio.sleep(0.05)
    if profile is not None:
        profile.disable()
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    decide.cancel()
    await asyncio.gather(decide, return_exceptions=True)
    await link.close()
    if vehicle.returncode != 0:
        raise SystemExit(f"the stand-in vehicle failed ({vehicle.returncode})")
    return cpu, wall


def _begin_search(mission: VehicleMission) -> None:
    """The search phase from the mission's position, as the lifecycle enters it once climbed.
    (The mission's state was a bare Control before the lifecycle machine: either is set, so
    that older commits run this script too, through PYTHONPATH.)"""
    pos = mission.seen.position
    assert pos is not None
    t = mission.seen.clock.now
    mission.seen.begin_search(t)
    mission.core.start(np.array([pos.north, pos.east]), t, [])
    searching = enter(mission.control, Phase.SEARCH)
    if hasattr(mission, "state"):
        mission.state = replace(mission.state, control=searching)
    else:
        setattr(mission, "control", searching)  # noqa: B010  (a plain attribute there)
    mission.sensors.select(mission.core.sensor(), t)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--answers", type=int, default=5000)
    p.add_argument("--profile", type=Path, help="write a CPU-time cProfile of the answering")
    args = p.parse_args()
    prof = cProfile.Profile(time.process_time) if args.profile else None
    with tempfile.TemporaryDirectory() as tmp:
        cpu, wall = asyncio.run(answer(args.answers, Path(tmp), prof))
    if prof is not None:
        prof.dump_stats(args.profile)
    n = args.answers - 1  # the first answer is not timed
    print(
        json.dumps(
            {
                "answers": n,
                "cpu_us_per_answer": round(cpu / n * 1e6, 1),
                "wall_us_per_answer": round(wall / n * 1e6, 1),
                "cpu_s_per_sim_s_at_10_hz": round(cpu / n * 10, 5),
                "profiled": prof is not None,
                "load_average_1min": round(os.getloadavg()[0], 2),
            }
        )
    )


if __name__ == "__main__":
    main()
