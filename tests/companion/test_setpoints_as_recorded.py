"""A seeded lockstep fleet mission flies as it did at the commit its record was made at.

The record (tests/data/setpoints-*.json, made by tests/setpoint_record.py, which says how to
make it again and what is compared) holds each vehicle's waypoints, velocity setpoints and
decisions in the search phase; each vehicle is compared up to its first detection (20-260 s of
search here). A change that alters what the companions send fails here.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path

from tests import setpoint_record

RECORD = Path(__file__).parent.parent / "data" / "setpoints-b12c0e8.json"


def test_the_seeded_mission_sends_the_recorded_setpoints(tmp_path: Path) -> None:
    record = json.loads(RECORD.read_text())
    flown = setpoint_record.fly(tmp_path / "mission")
    assert setpoint_record.differences(record["vehicles"], flown) == []
    # the mission compared is one that decides: a detection and several waypoints per vehicle
    for vehicle in flown.values():
        assert len(vehicle["waypoints"]) >= 5
        assert any(d["event"] == "detection" for d in vehicle["decisions"])


def test_a_changed_waypoint_velocity_or_decision_is_a_difference() -> None:
    before = json.loads(RECORD.read_text())["vehicles"]
    moved = copy.deepcopy(before)
    moved["1"]["waypoints"][2][1] += 0.5
    slower = copy.deepcopy(before)
    slower["0"]["velocities"]["100"][0] -= 0.1
    later = copy.deepcopy(before)
    later["2"]["decisions"][0]["t"] += 1.0
    assert setpoint_record.differences(before, before) == []
    for after, where in (
        (moved, "vehicle 1: waypoints"),
        (slower, "vehicle 0: velocity at 100"),
        (later, "vehicle 2: "),
    ):
        found = setpoint_record.differences(before, after)
        assert len(found) == 1, found
        assert found[0].startswith(where), found
