"""Operator commands over the Mosquitto on 127.0.0.1:1883 (flags, not a profile section): bad
payloads only give error events; pause holds the vehicle (no more setpoints: the emulator's
vehicle stops), resume flies on, abort returns it (RTL), land lands it."""

from __future__ import annotations

import json
import math
import os
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from companion.telemetry import events, read_log, read_records
from mdm_ground.fleet.runner import FleetOptions, run_fleet
from tests.mqtt_harness import Subscriber, publish, retained_topics
from tests.profile_files import write_profile_with
from tests.waiting import wait_until

pytestmark = pytest.mark.usefixtures("fleet_processes", "mqtt_broker")


@pytest.mark.timeout(120)
def test_pause_holds_resume_flies_abort_returns_land_lands(tmp_path: Path) -> None:
    prefix = f"mdm/test-{os.getpid()}-commands"
    profile = write_profile_with(tmp_path / "profile.yaml", "mqtt-command-test")
    out = tmp_path / "run"
    sub = Subscriber(1883, f"{prefix}/#", tmp_path / "sub.txt")

    def states(i: int) -> list[dict[str, Any]]:
        return [m.json() for m in sub.messages("state") if m.topic == f"{prefix}/uav{i}/state"]

    def phase(i: int) -> str | None:
        s = states(i)
        return str(s[-1]["phase"]) if s else None

    def command(i: int | str, payload: dict[str, str] | str) -> None:
        text = payload if isinstance(payload, str) else json.dumps(payload)
        done = publish(1883, f"{prefix}/{i}/cmd", text)
        assert done.returncode == 0, done.stderr

    fleet = threading.Thread(target=run_fleet, args=(FleetOptions(
        profile=str(profile), out=out, speedup=50.0, duration=5000.0, seed=4,
        wall_limit=100, mqtt_args=("--mqtt", "127.0.0.1:1883", "--mqtt-prefix", prefix,
                                   "--mqtt-state-rate", "10")),))  # fmt: skip
    try:
        sub.ready(1883, f"{prefix}/probe")
        fleet.start()
        wait_until(lambda: phase(0) == "search" and phase(1) == "search", 60, "both searching")
        command("uav1", "not json")
        command("uav1", {"command": "explode"})
        command("uav0", {"command": "pause", "id": "p1"})
        command("uav1", {"command": "abort", "id": "a1"})
        wait_until(lambda: phase(0) == "paused", 10, "vehicle 0 paused")
        held_from = len(states(0))
        time.sleep(1.5)  # about 75 sim s at 50x: 1.5 km of flight if it were still searching
        held = [s for s in states(0)[held_from:] if s["phase"] == "paused"]
        assert len(held) >= 5
        drift = max(
            math.dist((a["north"], a["east"]), (b["north"], b["east"])) for a in held for b in held
        )
        assert drift < 5.0, f"vehicle 0 moved {drift:.1f} m while paused"
        command("uav0", {"command": "resume", "id": "r1"})
        wait_until(lambda: phase(0) == "search", 20, "vehicle 0 searching again")
        here = held[-1]
        wait_until(
            lambda: (
                math.dist(
                    (here["north"], here["east"]), (states(0)[-1]["north"], states(0)[-1]["east"])
                )
                > 50.0
            ),
            20,
            "vehicle 0 moving again",
        )
        command("all", {"command": "land", "id": "l1"})
        fleet.join(60)
        assert not fleet.is_alive(), "the fleet did not end after abort and land"
    finally:
        sub.stop()
        retained_topics(1883, f"{prefix}/#", remove=True)
    assert retained_topics(1883, f"{prefix}/#") == [], "retained messages left on the broker"

    ends = json.loads((out / "results.json").read_text())["ends"]
    assert all(e["ok"] for e in ends), ends  # no companion had to be killed, none failed
    v0 = read_records(out / "mission-0.jsonl")
    v1 = read_records(out / "mission-1.jsonl")
    assert [(r["command"], r["id"]) for r in v0 if r["event"] == "command"] == [
        ("pause", "p1"),
        ("resume", "r1"),
        ("land", "l1"),
    ]
    logged = read_log(out / "mission-0.jsonl")
    assert events.PhaseChange("paused", by="operator") in logged.of(events.PhaseChange)
    assert [e.reason for e in logged.of(events.End)] == ["operator land"]
    errors = [r["error"] for r in v1 if r["event"] == "error"]
    assert len(errors) == 2, errors
    assert errors[0].startswith("not JSON"), errors
    assert errors[1] == "command 'explode': expected one of pause, resume, abort, land"
    assert [(r["command"], r["id"]) for r in v1 if r["event"] == "command"] == [("abort", "a1")]
    assert [e.reason for e in read_log(out / "mission-1.jsonl").of(events.End)] == [
        "operator abort"
    ]

    emulator = [r for r in read_records(out / "emulator-events.jsonl") if r["event"] == "mode"]
    modes = {i: [r["mode"] for r in emulator if r["vehicle"] == i] for i in (0, 1)}
    # land -> LAND; the PX4 persona, as PX4, holds once landed and disarmed (8a4eb55)
    assert modes[0][-4:] == ["HOLD", "OFFBOARD", "LAND", "HOLD"], modes[0]
    # abort -> RTL; the PX4 persona, as PX4, holds once landed and disarmed
    assert modes[1][-2:] == ["RTL", "HOLD"], modes[1]
