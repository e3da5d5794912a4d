"""Shared set-up of the emulator benchmarks: a sink process, a busy fleet, one pinned core."""

from __future__ import annotations

import asyncio
import json
import os
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from mdm_profiles import builtin_profile
from sim_vehicle_stub.config import EmulatorConfig
from sim_vehicle_stub.emulator import Emulator
from sim_vehicle_stub.vehicle import NeuSetpoint

SINK = Path(__file__).with_name("emulator_sink.py")


@dataclass(frozen=True)
class RunResult:
    vehicles: int
    speedup: float | None
    wall: float
    sim: float
    cpu: float
    rebases: int
    datagrams_per_vehicle_per_sim_s: float

    @property
    def ratio(self) -> float:
        return self.sim / self.wall

    @property
    def cpu_share(self) -> float:
        return self.cpu / self.wall

    @property
    def cpu_per_sim_s(self) -> float:
        """Core-seconds of CPU per sim second: below 1, one dedicated core keeps real time."""
        return self.cpu / self.sim


def load_note() -> str:
    """The machine's load, printed with every figure (this host is shared)."""
    one, five, _ = os.getloadavg()
    return f"load average {one:.1f} / {five:.1f} on {os.cpu_count()} cores"


def fly_everyone(emu: Emulator) -> None:
    """Arm every vehicle, switch its detection sensor on and send it across the area."""
    centre = (emu.scenario.area.north / 2, emu.scenario.area.east / 2)
    for v in emu.vehicles:
        for name in ("COM_OF_LOSS_T", "GUID_TIMEOUT"):
            if name in v.params:
                v.params.set(name, 1e9)
        v.params.set("MDM_SENSOR", 0)
        v.apply_params()  # (the failsafes and the sensor read the parameters from here)
        v.on_setpoint(NeuSetpoint(0.0, centre, None, 30.0, None, None))
        v.arm(True)
        v.set_mode(v.persona.mode(v.persona.external_mode))
        v.on_setpoint(NeuSetpoint(0.0, centre, None, 30.0, None, None))


def run(n: int, speedup: float | None, wall: float, base_port: int) -> RunResult:
    """Run ``n`` vehicles for about ``wall`` seconds into a sink; measure sim time and CPU."""
    sink = subprocess.Popen(
        [sys.executable, str(SINK), str(base_port), str(n)],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert sink.stdout is not None
    assert sink.stdout.readline().strip() == "ready"
    profile = builtin_profile("paper-fixed")
    cfg = EmulatorConfig(
        profile=profile,
        vehicles=n,
        base_port=base_port,
        bind_port_base=0,
        speedup=speedup,
        personas=("px4", "ardupilot"),
    )

    async def go() -> tuple[float, float, float, int]:
        emu = Emulator(cfg)
        fly_everyone(emu)
        await emu.start()
        cpu0, wall0, sim0 = time.process_time(), time.monotonic(), emu.clock.now
        await asyncio.sleep(wall)
        cpu, dt, sim = time.process_time() - cpu0, time.monotonic() - wall0, emu.clock.now - sim0
        rebases = emu.clock.rebases
        await emu.stop()
        return dt, sim, cpu, rebases

    try:
        dt, sim, cpu, rebases = asyncio.run(go())
    finally:
        sink.terminate()
        out, _ = sink.communicate(timeout=10)
    counts = json.loads(out.strip().splitlines()[-1])
    per = min(counts) / sim if sim > 0 else 0.0
    return RunResult(n, speedup, dt, sim, cpu, rebases, per)
