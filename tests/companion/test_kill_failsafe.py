"""``kill -9`` of the companion mid-search on the emulator's personas (the differential of
test_kill_failsafe_sitl.py): with the safety net the companion put into the vehicle before
arming (field-duebendorf: ``set`` by default), the persona returns by itself as its autopilot
does (PX4: offboard loss, COM_OBL_RC_ACT; ArduCopter: the GCS failsafe on the companion's
heartbeat, MAV_GCS_SYSID) and lands, disarmed. Judged from the emulated autopilot's own state,
never from the companion; no process of the companion goes on sending setpoints."""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import pytest

from companion.telemetry.mission_log import read_records
from mdm_profiles import load_profile
from sim_vehicle_stub.emulator import Emulator
from sim_vehicle_stub.personas.base import Behaviour
from tests.companion.test_sitl_flights import Companion
from tests.emulator_harness import free_udp_base, make_config, running_emulator
from tests.waiting import wait_until

SPEEDUP = 20.0
INSIDE = ((600.0, 1000.0),)  # inside the site's fence


def descendants(pid: int) -> list[int]:
    """Every live process below ``pid`` (its children's children too), from /proc."""
    parents: dict[int, int] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            parents[int(entry.name)] = int(stat.rsplit(")", 1)[1].split()[1])
    found, todo = [], [pid]
    while todo:
        p = todo.pop()
        kids = [c for c, parent in parents.items() if parent == p]
        found += kids
        todo += kids
    return found


def alive(pids: list[int]) -> list[int]:
    return [p for p in pids if Path(f"/proc/{p}").exists()]


def _searching(emu: Emulator) -> bool:
    v = emu.vehicles[0]
    return bool(v.armed and v.mode.behaviour is Behaviour.EXTERNAL and v.fleet.alt[0] > 38.0)


@pytest.mark.timeout(180)
@pytest.mark.parametrize("backend", ["pymavlink", pytest.param("mavsdk", marks=pytest.mark.slow)])
@pytest.mark.parametrize("persona", ["px4", "ardupilot"])
def test_a_killed_companion_leaves_the_persona_returning_and_landing(
    persona: str, backend: str, tmp_path: Path
) -> None:
    base = free_udp_base(1)
    config = make_config(
        1, base, profile=load_profile("field-duebendorf"), speedup=SPEEDUP,
        personas=(persona,), start_positions=INSIDE, events=tmp_path / "emulator-events.jsonl",
    )  # fmt: skip
    with running_emulator(config) as emu:
        v = emu.vehicles[0]
        comp = Companion(
            tmp_path, "field-duebendorf", 0, f"udpin:127.0.0.1:{base}", backend, duration=900.0,
            extra=("--sensor-source", "virtual"),
        )  # fmt: skip
        try:
            wait_until(lambda: _searching(emu), 90.0, "searching", context=comp.output)
            children = descendants(comp.process.pid)
            killed_sim = v.now
            os.killpg(comp.process.pid, signal.SIGKILL)
            comp.process.wait()
            killed = time.monotonic()
            wait_until(lambda: v.mode.behaviour is Behaviour.RTL, 30.0, "RTL", context=comp.output)
            to_rtl = (time.monotonic() - killed, v.now - killed_sim)
            wait_until(lambda: v.landed and not v.armed, 120.0, "landed and disarmed")
        finally:
            comp.kill()
        last = v.setpoint.t if v.setpoint is not None else None
    records = read_records(tmp_path / "emulator-events.jsonl")
    cause = [
        (e["cause"], e["action"], round(e["t"] - killed_sim, 1))
        for e in records
        if e["event"] == "failsafe"
    ]
    assert alive(children) == [], children
    assert last is None or last <= killed_sim + 1.0  # nothing streamed after the kill
    print(
        f"\n{persona} {backend}: kill -> RTL {to_rtl[0]:.1f} wall s / {to_rtl[1]:.1f} sim s "
        f"at {SPEEDUP:g}x; failsafe {cause[-1:]}; landed, disarmed"
    )
    # the companion-loss time the safety net wrote: 5 wall s (in sim s at the emulator's rate)
    assert to_rtl[0] < 10.0, to_rtl
    # the companion-loss failsafe, RTL, after the kill; ArduCopter's velocity target stops
    # after GUID_TIMEOUT first ('stop'), and on its way the vehicle may meet its fence (RTL)
    loss = "setpoint loss" if persona == "px4" else "link loss"
    assert (loss, "RTL") in [c[:2] for c in cause], cause
    assert all(c[1] in ("RTL", "stop") and c[2] >= 0 for c in cause), cause
