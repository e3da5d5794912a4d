"""docker/compose.yaml for real: the image built from a local Debian base, then broker (ACL and
password file), signed emulator and 3 companions brought up to a completed mission; the results
and the MQTT events are read from the host, and `down -v` leaves nothing behind.

Skipped only where no Docker engine (or no Compose v2) answers; `.ci/run` installs both."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from companion.telemetry import read_records
from mdm_ground.fleet.scoring import score
from mdm_profiles import load_profile
from tests.docker.stack import Stack, all_events, project
from tests.mqtt_harness import free_port, publish

VEHICLES = 3
COMPANIONS = [f"companion-{i}" for i in range(VEHICLES)]
SPEEDUP = "50"
"""Sim/wall ratio: the profile's 1000 s search and the flight home in well under a minute."""
MISSION_WALL_S = 240.0


@pytest.fixture
def stack(docker_images: None, tmp_path: Path) -> Iterator[Stack]:
    with project(
        "compose.yaml", tmp_path, list(range(VEHICLES)), free_port(), {"MDM_SPEEDUP": SPEEDUP}
    ) as stack:
        yield stack


@pytest.mark.timeout(900)
def test_compose_flies_a_signed_mission_with_events_on_the_broker(
    stack: Stack, tmp_path: Path
) -> None:
    passwords, port = stack.passwords, stack.port
    stack.compose("up", "-d", "mosquitto")
    stack.broker_ready()
    # the ACL and the password file are the broker's: a wrong password and a companion's
    # account (which may not command) are refused, the operator is not
    wrong = publish(port, "mdm/paper-fixed/uav0/cmd", "{}", user="operator", password="wrong")
    assert wrong.returncode != 0, "the broker took a wrong password"
    sub = stack.subscriber("mdm/#", tmp_path / "mqtt.txt", "monitor")
    spy = stack.subscriber("mdm/+/+/cmd", tmp_path / "cmd.txt", "operator")
    publish(
        port,
        "mdm/paper-fixed/uav1/cmd",
        '{"command": "abort"}',
        user="uav0",
        password=passwords["uav0"],
    )
    start = time.monotonic()
    stack.compose("up", "-d")
    codes = stack.wait_exit(COMPANIONS, MISSION_WALL_S)
    print(f"mission (up to the last companion's exit): {time.monotonic() - start:.1f} s")
    assert codes == ["0"] * VEHICLES, (
        f"companion exit codes {codes}\n" + stack.compose("logs", "--tail", "8", *COMPANIONS).stdout
    )
    assert all(m.topic.startswith("mdm/probe/") for m in spy.messages()), (
        "a companion's account published a command"
    )
    runs = tmp_path / "runs"
    stack.compose("cp", "companion-0:/home/mdm/runs", str(runs))
    profile = load_profile("paper-fixed")
    result = score(profile, runs, VEHICLES, profile.mission.duration)
    print(
        f"T_nc {result.tnc} of {len(profile.targets)} in {profile.mission.duration:.0f} s "
        f"by {VEHICLES} vehicles; confirmations {len(result.confirmations)}, false "
        f"{result.false_confirmations}; end {result.end_reasons}"
    )
    assert result.end_reasons == dict.fromkeys(range(VEHICLES), "mission time")
    assert result.false_confirmations == 0
    assert "MAVLink signing on" in stack.compose("logs", "emulator").stdout
    assert any(read_records(runs / "emulator-events.jsonl")), "the emulator logged nothing"
    for i in range(VEHICLES):
        logged = [r for r in read_records(runs / f"mission-{i}.jsonl") if r["event"] != "tick"]
        events = all_events(sub, f"mdm/paper-fixed/uav{i}/event", len(logged))
        assert [e["seq"] for e in events] == list(range(len(logged)))
        published = [{k: v for k, v in e.items() if k != "seq"} for e in events]
        assert published == [{**r, "vehicle": i} for r in logged], f"uav{i}: MQTT != log"
        states = [m.json() for m in sub.messages("state") if f"/uav{i}/" in m.topic]
        assert {s["phase"] for s in states} >= {"search", "return"}, f"uav{i} states"
