"""MQTT detections published by the test (mosquitto_pub, real Mosquitto on 127.0.0.1:1883) drive
the companion's level switch and a confirmation on the emulator; a bad payload is an error
event and ignored; a silent detector is reported and heard again."""

from __future__ import annotations

import json
import os
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from companion.link.local_frame import LocalFrame
from companion.telemetry import events, read_log, read_records
from mdm_ground.fleet.runner import FleetOptions, run_fleet
from mdm_profiles import load_profile
from tests.emulator_harness import free_udp_base
from tests.mqtt_harness import Subscriber, publish
from tests.profile_files import levels, write_profile_with
from tests.waiting import wait_until

pytestmark = pytest.mark.usefixtures("fleet_processes", "mqtt_broker")


@pytest.mark.timeout(120)
def test_mqtt_detections_switch_the_level_and_confirm(tmp_path: Path) -> None:
    prefix = f"mdm/test-{os.getpid()}-detections"
    path = write_profile_with(
        tmp_path / "profile.yaml",
        "mqtt-sensor-test",
        targets=[{"north": 1500.0, "east": 1500.0}],
        fleet={"vehicles": 1},
        sensor_source={"kind": "mavlink", "silence_timeout": 1.0},
        policy={"levels": levels(600.0, 300.0, 5000.0)},
    )
    profile = load_profile(path)
    out = tmp_path / "run"
    sub = Subscriber(1883, f"{prefix}/#", tmp_path / "sub.txt")
    topic = f"{prefix}/uav0/detections"

    def state() -> dict[str, Any]:
        states = [m.json() for m in sub.messages("state")]
        return states[-1] if states else {}

    def detect(data: dict[str, Any] | str) -> None:
        text = data if isinstance(data, str) else json.dumps(data)
        done = publish(1883, topic, text)
        assert done.returncode == 0, done.stderr

    # The profile says mavlink: the flag (passed through by the fleet) chooses mqtt.
    fleet = threading.Thread(target=run_fleet, args=(FleetOptions(
        profile=str(path), out=out, speedup=20.0, duration=5000.0, base_port=free_udp_base(1),
        seed=5, wall_limit=100, sensor_source="mqtt",
        mqtt_args=("--mqtt", "127.0.0.1:1883", "--mqtt-prefix", prefix,
                   "--mqtt-state-rate", "10")),))  # fmt: skip
    try:
        sub.ready(1883, f"{prefix}/probe")
        fleet.start()
        wait_until(lambda: state().get("phase") == "search", 60, "vehicle 0 searching")
        mission_log = out / "mission-0.jsonl"
        wait_until(
            lambda: any(r.get("state") == "silent" for r in read_records(mission_log)),
            10,
            "the silent detector reported",
        )
        assert state()["level"] == 0
        detect("not json")
        detect({"time": time.time(), "sensor": "detection"})  # nothing seen: alive again
        # A confirmation-sensor report while the detection sensor is on is not a contact.
        detect({"time": time.time(), "sensor": "confirmation", "north": 1500.0, "east": 1500.0})
        detect(
            {
                "time": time.time(),
                "sensor": "detection",
                "north": 1500.0,
                "east": 1500.0,
                "confidence": 0.9,
            }
        )
        wait_until(lambda: state().get("level") == 1, 10, "level 1 after the detection")
        assert state()["found"] == 0
        frame = LocalFrame(profile.origin.lat, profile.origin.lon, profile.origin.alt)
        lat, lon, _ = frame.to_geodetic(1500.0, 1500.0, 0.0)
        detect({"time": time.time(), "sensor": "confirmation", "lat": lat, "lon": lon})
        fleet.join(60)
        assert not fleet.is_alive(), "the mission did not end after the confirmation"
    finally:
        sub.stop()

    records = read_records(out / "mission-0.jsonl")
    kinds = [r["event"] for r in records]
    logged = read_log(out / "mission-0.jsonl")
    assert [e.reason for e in logged.of(events.End)] == ["all targets"]
    (confirmation,) = logged.of(events.Confirmation)
    assert abs(confirmation.north - 1500.0) < 0.01
    assert abs(confirmation.east - 1500.0) < 0.01
    errors = [r for r in records if r["event"] == "error"]
    assert [(e["source"], e["error"][:8]) for e in errors] == [("detector", "not JSON")]
    detector = [r["state"] for r in records if r["event"] == "detector"]
    assert detector[:2] == ["silent", "alive"]
    assert kinds.index("detection") < kinds.index("confirmation")
    emulator = read_records(out / "emulator-events.jsonl")
    assert not [r for r in emulator if r["event"] in ("entered_range", "confirmed")]
