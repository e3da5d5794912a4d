"""A two-vehicle fleet with the profile's mqtt: section against the Mosquitto on 127.0.0.1:1883:
an independent subscriber (mosquitto_sub) gets every mission-log event, numbered and in order,
state messages at the profile's rate, and a retained online/offline status."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import pytest

from companion.telemetry import read_records
from mdm_ground.fleet.runner import FleetOptions, run_fleet
from tests.mqtt_harness import Subscriber, retained_topics
from tests.profile_files import sensors, write_profile_with
from tests.waiting import wait_until

pytestmark = pytest.mark.usefixtures("fleet_processes", "mqtt_broker")


def mqtt_events(sub: Subscriber, prefix: str, vehicle: int) -> list[dict[str, Any]]:
    """The vehicle's events, first copy of each seq (QoS 1 may deliver twice), arrival order."""
    seen: set[int] = set()
    out = []
    for m in sub.messages("event"):
        if m.topic == f"{prefix}/uav{vehicle}/event":
            e = m.json()
            if e["seq"] not in seen:
                seen.add(e["seq"])
                out.append(e)
    return out


def log_events(path: Path) -> list[dict[str, Any]]:
    return [r for r in read_records(path) if r["event"] != "tick"]


@pytest.mark.timeout(120)
def test_fleet_publishes_every_event_in_order_state_and_status(tmp_path: Path) -> None:
    prefix = f"mdm/test-{os.getpid()}-fleet"
    profile = write_profile_with(
        tmp_path / "profile.yaml",
        "mqtt-fleet-test",
        targets=[
            {"north": 1500.0, "east": 1500.0},
            {"north": 700.0, "east": 700.0},
            {"north": 600.0, "east": 2400.0, "false_target": True},
        ],
        sensors=sensors(1000.0, 200.0),
        policy={"memory_radius": 300.0},
        mission={"duration": 600.0},
        mqtt={"host": "127.0.0.1", "port": 1883, "topic_prefix": prefix, "state_rate": 5.0},
    )
    sub = Subscriber(1883, f"{prefix}/#", tmp_path / "sub.txt")
    try:
        sub.ready(1883, f"{prefix}/probe")
        run_fleet(
            FleetOptions(
                profile=str(profile),
                out=tmp_path / "run",
                speedup=50.0,
                duration=200.0,
                seed=3,
                wall_limit=90,
            )
        )

        def offline(i: int) -> bool:
            status = [m.json() for m in sub.messages("status") if f"/uav{i}/" in m.topic]
            return bool(status) and status[-1] == {"vehicle": i, "state": "offline", "clean": True}

        wait_until(lambda: offline(0) and offline(1), 15, "both vehicles' clean offline status")
    finally:
        sub.stop()
        retained_topics(1883, f"{prefix}/#", remove=True)
    assert retained_topics(1883, f"{prefix}/#") == [], "retained messages left on the broker"
    for i in range(2):
        logged = log_events(tmp_path / "run" / f"mission-{i}.jsonl")
        published = mqtt_events(sub, prefix, i)
        assert [e["seq"] for e in published] == list(range(len(logged)))
        assert [{k: v for k, v in e.items() if k != "seq"} for e in published] == [
            r | {"vehicle": i} for r in logged
        ]
        names = {e["event"] for e in published}
        assert {"start", "phase", "level", "end"} <= names, names
        assert published[-1]["event"] == "exit"  # the last record a companion writes
        assert published[-1]["status"] == 0, published[-1]

        states = [m.json() for m in sub.messages("state") if f"/uav{i}/" in m.topic]
        assert len(states) >= 10, f"vehicle {i}: only {len(states)} state messages"
        assert any(s["phase"] == "search" and s["mode"] == "OFFBOARD" for s in states)
        for s in states:
            assert {"t", "phase", "mode", "level", "sensor", "ci", "found"} <= s.keys(), s
            # C_I exists on level 2 only (0-based level 1), and lies in (0, index_max]
            assert (s["ci"] is None) == (s["level"] == 0), s
            assert s["ci"] is None or 0.0 < s["ci"] <= 0.95, s
        times = [s["t"] for s in states]
        assert times == sorted(times), "state messages out of order"
        status = [m.json()["state"] for m in sub.messages("status") if f"/uav{i}/" in m.topic]
        assert status[-2:] == ["online", "offline"], status
