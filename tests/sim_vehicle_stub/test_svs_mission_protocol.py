"""The emulator's mission protocol gives the answers measured on the real autopilots (the walk
of tests/mission_script.py against ArduCopter 4.7-dev and PX4 1.16-dev SITL; the SITL lane's
test_svs_mission_differential.py compares the whole walk). Here: the answers in which the two
autopilots differ, each as its SITL gave it."""

from __future__ import annotations

from typing import Any

import pytest

from tests.emulator_harness import free_udp_base, make_config, running_emulator
from tests.mission_script import MissionClient, walk

REQ, REQ_INT = "MISSION_REQUEST", "MISSION_REQUEST_INT"
ACCEPTED, UNSUPPORTED_FRAME, UNSUPPORTED, NO_SPACE = 0, 2, 3, 4
MEASURED: dict[str, dict[str, Any]] = {
    "ardupilot": {
        # Home is item 0 from boot; every item is asked for with the legacy MISSION_REQUEST.
        "empty download": [("MISSION_ITEM_INT", 16)],
        "upload int, RTL in MISSION frame": ([f"{REQ}:{i}" for i in range(5)], ACCEPTED),
        "upload int, RTL in a global frame": ([f"{REQ}:{i}" for i in range(5)], ACCEPTED),
        "mission current total": 4,
        "upload frame 12": ([f"{REQ}:0", f"{REQ}:1"], UNSUPPORTED_FRAME),
        "upload command 31999": ([f"{REQ}:0", f"{REQ}:1"], UNSUPPORTED),
        "partial 1..2": ([f"{REQ}:1", f"{REQ}:2"], ACCEPTED),
        "request past end": "MISSION_ACK:13",
        "DO_SET_MISSION_CURRENT 2": 0,
        "mission current after set 2": 2,
        "DO_SET_MISSION_CURRENT 99": 2,
        "upload fence with a waypoint": ([f"{REQ}:0"], UNSUPPORTED),
        "DO_FENCE_ENABLE 1": 0,
        "fence bits enabled": (True, True, True),
        "fence bits disabled": (True, False, True),
        "CONDITION_YAW": 0,
        "clear all": UNSUPPORTED,
        "upload count 60000": ([], NO_SPACE),
    },
    "px4": {
        # PX4 asks the way the client's last item (or request) came, legacy after boot.
        "empty download": [],
        "upload int, RTL in MISSION frame": ([f"{REQ}:0"] + [f"{REQ_INT}:{i}" for i in range(1, 5)], ACCEPTED),
        "upload legacy": ([f"{REQ}:{i}" for i in range(5)], ACCEPTED),
        "upload int, RTL in a global frame": ([f"{REQ}:0"] + [f"{REQ_INT}:{i}" for i in range(1, 5)], UNSUPPORTED),
        "mission current total": 5,
        "upload frame 12": ([f"{REQ_INT}:0", f"{REQ_INT}:1"], UNSUPPORTED_FRAME),
        "request past end": "none",
        "fence bits enabled": (False, False, False),
        "upload fence with a waypoint": ([f"{REQ}:0"], ACCEPTED),
        "DO_FENCE_ENABLE 1": 3,
        "CONDITION_YAW": 3,
        "clear all": ACCEPTED,
        "download after clear": [],
    },
}  # fmt: skip


def _json_like(x: Any) -> Any:
    """Tuples as lists, as the SITL measurements were stored."""
    if isinstance(x, (list, tuple)):
        return [_json_like(v) for v in x]
    return x


@pytest.mark.timeout(90)
@pytest.mark.parametrize("persona", ["ardupilot", "px4"])
def test_mission_protocol_answers_are_the_real_autopilots(persona: str) -> None:
    base = free_udp_base(1)
    with running_emulator(make_config(1, base, personas=(persona,), speedup=5.0)):
        c = MissionClient(f"udpin:127.0.0.1:{base}", 1)
        try:
            c.wait_home(10.0)
            got = walk(c)
        finally:
            c.close()
    for key, expected in MEASURED[persona].items():
        assert _json_like(got[key]) == _json_like(expected), key
