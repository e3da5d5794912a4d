"""Differential test: the same scripted flight (tests/flight_script.py) on the emulator's
persona and on the real autopilot's SITL (ArduCopter at 5x, PX4 SIH at 4x). Command results and
the mode sequence must be identical; climb rate, cruise speed, top speed and the time to reach
a position setpoint agree within the tolerances below (the emulator flies the paper's tau-lag
model, not the autopilots' jerk-limited controllers). docs/protocol.md has the measured table."""

from __future__ import annotations

import functools
import logging
from collections.abc import Callable
from dataclasses import asdict

import pytest

from tests.emulator_harness import free_udp_base, make_config, running_emulator
from tests.flight_script import Flight, Record, fly_ardupilot, fly_px4
from tests.sitl import SitlInstance

log = logging.getLogger(__name__)
PERSONA = {"arducopter": "ardupilot", "px4": "px4"}
SPEEDUP = {"arducopter": 5.0, "px4": 4.0}
"""Both autopilots fly this script stably at these speed-ups here (PX4 SIH through
PX4_SIM_SPEED_FACTOR); the emulator runs at the same one."""
HOME_AMSL = 488.0
"""The emulator profile's origin altitude; the SITLs are started at the same altitude."""
TOLERANCE = {
    "arducopter": {"climb_rate": 0.15, "cruise_speed": 0.10, "top_speed": 0.10,
                   "time_to_setpoint": 0.30},
    "px4": {"climb_rate": 0.30, "cruise_speed": 0.25, "top_speed": 0.10,
            "time_to_setpoint": 0.30},
}  # fmt: skip
"""Relative differences allowed, emulator vs SITL, from repeated measurements plus a margin
(docs/protocol.md, differential table): the speed caps agree within 5 %; ArduCopter's
jerk-limited acceleration and braking make it reach a setpoint 150 m away ~20 % later than the
critically damped lag loop; PX4's takeoff ramps from MPC_TKO_SPEED towards MPC_Z_V_AUTO_UP
(13-22 % faster in four runs than the persona's constant MPC_TKO_SPEED) and its SIH airframe answers a
5 m/s OFFBOARD velocity setpoint slowly (4.2-4.45 m/s after 10 s, 12-16 % under)."""


def _fly(kind: str, url: str, sysid: int, wall_timeout: float) -> Record:
    flight = Flight(url, sysid, wall_timeout)
    try:
        if kind == "arducopter":
            return fly_ardupilot(flight)
        return fly_px4(flight, HOME_AMSL)
    finally:
        flight.close()


@pytest.mark.timeout(600)
@pytest.mark.parametrize("autopilot", ["arducopter", "px4"])
def test_emulator_persona_flies_the_script_like_the_real_autopilot(
    autopilot: str, sitl_start: Callable[..., SitlInstance], monkeypatch: pytest.MonkeyPatch
) -> None:
    factory = functools.partial(sitl_start, autopilot)
    speedup = SPEEDUP[autopilot]
    base = free_udp_base(1)
    cfg = make_config(1, base, personas=(PERSONA[autopilot],), speedup=speedup)
    with running_emulator(cfg):
        emulated = _fly(autopilot, f"udpin:127.0.0.1:{base}", 1, 240.0)
    home = f"47.397742,8.545594,{HOME_AMSL}" + (",0" if autopilot == "arducopter" else "")
    if autopilot == "px4":
        monkeypatch.setenv("PX4_SIM_SPEED_FACTOR", str(speedup))
        inst = factory(home=home)
    else:
        inst = factory(home=home, speedup=speedup)
    real = _fly(autopilot, inst.companion_url, inst.sysid, 300.0)
    log.info("%s emulated %s", autopilot, asdict(emulated))
    log.info("%s real     %s", autopilot, asdict(real))
    print(f"\n{autopilot} emulated {asdict(emulated)}\n{autopilot} real     {asdict(real)}")
    assert emulated.results == real.results
    assert emulated.modes == real.modes
    assert emulated.landed_disarmed
    assert real.landed_disarmed
    for key, tol in TOLERANCE[autopilot].items():
        e, r = getattr(emulated, key), getattr(real, key)
        assert e == pytest.approx(r, rel=tol), f"{key}: emulator {e:.2f}, {autopilot} {r:.2f}"
