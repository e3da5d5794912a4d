"""The floor of the lockstep fleet: the emulator with 12 vehicles, each answered by a process
that does nothing but answer.

    cd benchmarks && ../.venv/bin/python fleet_floor.py [--speedup 100|max] [--wall 8]

Every vehicle flies in the external mode (armed, sensors on, as in emulator_speedup.py), streams
what a fleet companion leaves on (LOCAL_POSITION_NED at 10 Hz, HEARTBEAT and SYS_STATUS at
1 Hz, the sensor's readings), and the emulator runs in lockstep: each telemetry tick waits
until every vehicle has answered. Each vehicle is answered by its own process, as the fleet's
companions do; the first two kinds do no work: on every telemetry datagram they send one
ready-made SET_POSITION_TARGET_LOCAL_NED back (one of 256 frames packed before the run, one per
sequence number). The kinds (``--kinds``):

- ``blocking``: a plain blocking ``recvfrom`` / ``sendto`` loop; the least a Python process
  can do per answer;
- ``asyncio``: the same inside an asyncio DatagramProtocol, as the companion receives;
- ``essential``: the asyncio answerer doing the companion's own per-answer work and nothing
  else: its frame split and decode (``fast_frames``), pursuit guidance inside a geofence, the
  setpoint's encode and the .tlog; no events, lifecycle, sensors or policy check;
- ``none``: no answerer and no lockstep (the emulator alone, its telemetry drained by the sink).

Printed per kind: sim/wall, the emulator's CPU s per sim s and the answerers' (their sum), and
the bound 2 cores give at that total. No scheduling gets the fleet below the ``asyncio`` total;
the gap between ``essential`` and a real companion (companion_fleet_speed.py) is its framework
(events, lifecycle, sensors, policy check).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import subprocess
import sys
import time
from pathlib import Path

from emulator_common import SINK, fly_everyone, load_note

from companion.link.mavlink_commands import GLOBAL_POSITION_INT, UNREAD_STREAMS
from mdm_profiles import builtin_profile
from sim_vehicle_stub.config import EmulatorConfig, system_id
from sim_vehicle_stub.emulator import Emulator

N = 12
UNREAD = (*UNREAD_STREAMS, GLOBAL_POSITION_INT)
"""What a fleet companion switches off on its dedicated link (paper-fixed has no fence watch)."""

ANSWERER = r"""
import asyncio, socket, sys
from pymavlink.dialects.v20 import ardupilotmega as mavlink2
kind, port, sysid = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
mav = mavlink2.MAVLink(None, srcSystem=255, srcComponent=190)
frames = []
for _ in range(256):
    msg = mav.set_position_target_local_ned_encode(0, sysid, 1, 1, 0b110111111000,
                                                  500.0, 500.0, -30.0, 0, 0, 0, 0, 0, 0, 0, 0)
    frames.append(bytes(msg.pack(mav)))
sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
sock.bind(("127.0.0.1", port))
print("ready", flush=True)
if kind == "blocking":
    k = 0
    while True:
        data, addr = sock.recvfrom(4096)
        sock.sendto(frames[k], addr)
        k = (k + 1) & 0xFF
elif kind == "asyncio":
    class Answer(asyncio.DatagramProtocol):
        k = 0
        def connection_made(self, transport):
            self.transport = transport
        def datagram_received(self, data, addr):
            self.transport.sendto(frames[self.k], addr)
            self.k = (self.k + 1) & 0xFF
else:  # essential: the companion's own decode, guidance, encode and .tlog, nothing else
    import tempfile
    from pathlib import Path
    import numpy as np
    from companion.geofence import Geofence
    from companion.guidance import GuidanceConfig, pursuit
    from companion.link import fast_frames
    from mavlink_wire import frames as wire
    from companion.link.tlog import TelemetryLog
    fence = Geofence.rectangle(20000.0, 20000.0)
    guide = GuidanceConfig(speed=20.0, altitude=30.0, acceptance_radius=5.0)
    goal = np.array([5000.0, 15000.0])
    tlog = TelemetryLog(Path(tempfile.mkdtemp()) / "v.tlog")
    class Answer(asyncio.DatagramProtocol):
        k = 0
        def connection_made(self, transport):
            self.transport = transport
        def datagram_received(self, data, addr):
            position = None
            for msg_id, _, frame in wire.split(data) or ():
                tlog.write(frame)
                fields = fast_frames.unpack(msg_id, frame)
                if msg_id == fast_frames.LOCAL_POSITION_NED:
                    position = fields
            if position is None:
                return
            t, north, east, down = position[:4]
            sp = pursuit(np.array([north, east]), down, goal, guide, fence, 0.1)
            payload = fast_frames.SETPOINT.pack(t, sp.north, sp.east, sp.down, sp.vn, sp.ve,
                                                sp.vd, 0.0, 0.0, 0.0, 0.0, 0.0, 3527, sysid, 1, 1)
            out = fast_frames.frame(fast_frames.SET_POSITION_TARGET_LOCAL_NED, payload, self.k,
                                    255, 190)
            tlog.write(out)
            self.transport.sendto(out, addr)
            self.k = (self.k + 1) & 0xFF
if kind != "blocking":
    async def main():
        loop = asyncio.get_running_loop()
        await loop.create_datagram_endpoint(Answer, sock=sock)
        await asyncio.Event().wait()
    asyncio.run(main())
"""


def run(kind: str, speedup: float | None, wall: float, base_port: int) -> dict[str, object]:
    if kind == "none":
        procs = [
            subprocess.Popen(
                [sys.executable, str(SINK), str(base_port), str(N)],
                stdout=subprocess.PIPE,
                text=True,
            )
        ]
    else:
        procs = [
            subprocess.Popen(
                [sys.executable, "-c", ANSWERER, kind, str(base_port + i), str(system_id(i))],
                stdout=subprocess.PIPE,
                text=True,
            )
            for i in range(N)
        ]
    for p in procs:
        assert p.stdout is not None
        assert p.stdout.readline().strip() == "ready"
    cfg = EmulatorConfig(
        profile=builtin_profile("paper-fixed"),
        vehicles=N,
        base_port=base_port,
        bind_port_base=0,
        speedup=speedup,
        personas=("px4", "ardupilot"),
        lockstep=kind != "none",
    )

    async def go() -> tuple[float, float, float, float, int, int]:
        emu = Emulator(cfg)
        fly_everyone(emu)
        for node in emu.nodes:  # what a fleet companion switches off (configure_streams)
            for msg_id in UNREAD:
                node.schedule.set_interval(msg_id, -1)
        await emu.start()
        await asyncio.sleep(1.0)  # every answerer known to its vehicle
        cpu0, wall0, sim0 = time.process_time(), time.monotonic(), emu.clock.now
        kids0 = [_proc_cpu(p.pid) for p in procs]
        await asyncio.sleep(wall)
        kids = sum(_proc_cpu(p.pid) - k0 for p, k0 in zip(procs, kids0, strict=True))
        cpu, dt, sim = time.process_time() - cpu0, time.monotonic() - wall0, emu.clock.now - sim0
        waits, nacks = emu.lockstep_waits, emu.stats()["totals"]["nacks"]
        await emu.stop()
        return dt, sim, cpu, kids, waits, nacks

    try:
        dt, sim, cpu, kids, waits, nacks = asyncio.run(go())
    finally:
        for p in procs:
            p.terminate()
            p.communicate(timeout=10)
    total = (cpu + kids) / sim
    return {
        "answerer": kind,
        "speedup_requested": speedup,
        "sim_wall": round(sim / dt, 1),
        "cpu_s_per_sim_s_emulator": round(cpu / sim, 5),
        "cpu_s_per_sim_s_answerers": round(kids / sim, 5),
        "cpu_s_per_sim_s_total": round(total, 5),
        "bound_2_cores": round(2 / total, 1),
        "us_per_answer_answerer": round(kids / sim / (10 * N) * 1e6, 1),
        "us_per_vehicle_tick_emulator": round(cpu / sim / (10 * N) * 1e6, 1),
        "lockstep_waits_per_sim_s": round(waits / sim, 1),
        "setpoints_refused": nacks,
    }


def _proc_cpu(pid: int) -> float:
    """User + system CPU seconds of a running process (from /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _speedup(text: str) -> float | None:
    return None if text == "max" else float(text)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--speedup", type=_speedup, default=100.0, help="a ratio, or max: flat out")
    p.add_argument("--wall", type=float, default=8.0, help="wall seconds measured per kind")
    p.add_argument("--kinds", default="none,blocking,asyncio,essential")
    args = p.parse_args()
    for kind in args.kinds.split(","):
        print(load_note(), flush=True)
        print(json.dumps(run(kind, args.speedup, args.wall, 33000)), flush=True)
    print(load_note())


if __name__ == "__main__":
    main()
