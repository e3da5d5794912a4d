"""Differential test of the mission protocol: the same walk (tests/mission_script.py: uploads
of missions, fences and rally points as INT and legacy float items, downloads, a partial list,
refusals, MISSION_CURRENT, the mission and fence commands, SYS_STATUS's geofence bits) against
the emulator's persona and against the real autopilot's SITL; every answer must be the same,
except the differences docs/protocol.md names (listed here)."""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

import pytest

from tests.emulator_harness import free_udp_base, make_config, running_emulator
from tests.mission_script import MissionClient, walk
from tests.sitl import SitlInstance

log = logging.getLogger(__name__)
PERSONA = {"arducopter": "ardupilot", "px4": "px4"}
HOME = "47.397742,8.545594,488"
NAMED_DIFFERENCES = {
    "arducopter": {"fence bits at boot"},
}
"""ArduCopter SITL boots with FENCE_ENABLE 0; the emulator's ArduPilot persona with 1 (its
search-area fence is on by default: docs/protocol.md, *Parameters*)."""


def _walk(url: str, sysid: int, ready_s: float) -> dict[str, Any]:
    c = MissionClient(url, sysid)
    try:
        c.wait_home(ready_s)
        return walk(c)
    finally:
        c.close()


@pytest.mark.timeout(400)
@pytest.mark.parametrize("autopilot", ["arducopter", "px4"])
def test_emulator_answers_the_mission_protocol_like_the_real_autopilot(
    autopilot: str, sitl_start: Callable[..., SitlInstance]
) -> None:
    base = free_udp_base(1)
    with running_emulator(make_config(1, base, personas=(PERSONA[autopilot],), speedup=5.0)):
        emulated = _walk(f"udpin:127.0.0.1:{base}", 1, 10.0)
    inst = sitl_start(autopilot, home=HOME + (",0" if autopilot == "arducopter" else ""))
    real = _walk(inst.companion_url, inst.sysid, 150.0)
    skip = NAMED_DIFFERENCES.get(autopilot, set())
    differ = {
        k: (emulated[k], real.get(k))
        for k in emulated
        if k not in skip and emulated[k] != real.get(k)
    }
    for k, (e, r) in differ.items():
        log.warning("%s %s: emulator %s, SITL %s", autopilot, k, e, r)
    print(f"\n{autopilot}: {len(emulated)} answers, {len(differ)} differ")
    assert not differ, inst.log()[-1500:]
    assert len(real) == len(emulated)
