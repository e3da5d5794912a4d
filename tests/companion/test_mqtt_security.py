"""docker/mosquitto/acl on a broker of its own with a fresh password file: the companion flies
with its own account; anonymous clients, a wrong password, another vehicle's account and the
vehicle's own account cannot command it or forge its events; the operator can."""

from __future__ import annotations

import json
import subprocess
import threading
from collections.abc import Callable
from pathlib import Path

import pytest

from companion.telemetry import events, read_log, read_records
from mdm_ground.fleet.runner import FleetOptions, run_fleet
from tests.mqtt_harness import Broker, Subscriber, publish
from tests.profile_files import levels, sensors, write_profile_with
from tests.waiting import wait_until

pytestmark = pytest.mark.usefixtures("fleet_processes")

ACL = Path(__file__).resolve().parents[2] / "docker" / "mosquitto" / "acl"
PREFIX = "mdm/secure"
PASSWORDS = {"operator": "op-secret", "uav0": "uav0-secret", "uav1": "uav1-secret"}


def _password_file(path: Path) -> None:
    for n, (user, password) in enumerate(PASSWORDS.items()):
        create = ["-c"] if n == 0 else []
        subprocess.run(["mosquitto_passwd", *create, "-b", str(path), user, password], check=True)


@pytest.mark.timeout(120)
def test_only_the_operator_commands_and_vehicles_publish_only_their_own(
    mosquitto: Callable[..., Broker], tmp_path: Path
) -> None:
    passwd = tmp_path / "passwd"
    _password_file(passwd)
    (tmp_path / "uav0.pw").write_text(PASSWORDS["uav0"] + "\n")
    profile = write_profile_with(
        tmp_path / "profile.yaml",
        "mqtt-security-test",
        targets=[{"north": 2950.0, "east": 2950.0}],
        fleet={"vehicles": 1},
        sensors=sensors(500.0, 50.0),
        policy={"levels": levels(600.0, 300.0, 30.0)},
    )
    out = tmp_path / "run"
    broker = mosquitto(security=f"allow_anonymous false\npassword_file {passwd}\nacl_file {ACL}\n")
    broker.start()
    op = {"user": "operator", "password": PASSWORDS["operator"]}
    sub = Subscriber(
        broker.port, "mdm/#", tmp_path / "sub.txt", user="operator", password=PASSWORDS["operator"]
    )

    def pause(**auth: str) -> subprocess.CompletedProcess[str]:
        msg = json.dumps({"command": "pause", "id": auth.get("user", "anonymous")})
        return publish(broker.port, f"{PREFIX}/uav0/cmd", msg, **auth)

    def phase() -> str | None:
        states = [m.json() for m in sub.messages("state")]
        return str(states[-1]["phase"]) if states else None

    fleet = threading.Thread(target=run_fleet, args=(FleetOptions(
        profile=str(profile), out=out, speedup=20.0, duration=5000.0, seed=6,
        wall_limit=100, mqtt_args=(
            "--mqtt", f"127.0.0.1:{broker.port}", "--mqtt-prefix", PREFIX,
            "--mqtt-username", "uav{vehicle}",
            "--mqtt-password-file", str(tmp_path / "uav{vehicle}.pw"))),
    ))  # fmt: skip
    try:
        sub.ready(
            broker.port, f"{PREFIX}/probe/cmd", user="operator", password=PASSWORDS["operator"]
        )
        fleet.start()
        wait_until(lambda: phase() == "search", 60, "vehicle 0 searching (its account publishes)")

        anonymous = pause()
        assert anonymous.returncode != 0
        assert "not authori" in anonymous.stderr
        wrong_password = pause(user="operator", password="guess")
        assert wrong_password.returncode != 0
        # accepted by the broker at the protocol level, dropped by the ACL
        assert pause(user="uav1", password=PASSWORDS["uav1"]).returncode == 0
        assert pause(user="uav0", password=PASSWORDS["uav0"]).returncode == 0
        forged = json.dumps({"seq": 0, "vehicle": 0, "t": 0.0, "event": "forged"})
        uav1 = {"user": "uav1", "password": PASSWORDS["uav1"]}
        assert publish(broker.port, f"{PREFIX}/uav0/event", forged, **uav1).returncode == 0
        assert publish(broker.port, f"{PREFIX}/uav0/status", forged, **uav1).returncode == 0

        assert pause(**op).returncode == 0
        wait_until(lambda: phase() == "paused", 10, "vehicle 0 paused by the operator")
        assert (
            publish(broker.port, f"{PREFIX}/all/cmd", '{"command": "abort"}', **op).returncode == 0
        )
        fleet.join(60)
        assert not fleet.is_alive()
    finally:
        sub.stop()
        broker.stop()

    log = read_records(out / "mission-0.jsonl")
    assert [(r["command"], r["id"]) for r in log if r["event"] == "command"] == [
        ("pause", "operator"),
        ("abort", None),
    ]
    assert [e.reason for e in read_log(out / "mission-0.jsonl").of(events.End)] == [
        "operator abort"
    ]
    commands = [m.json() for m in sub.messages("cmd") if m.topic != f"{PREFIX}/probe/cmd"]
    assert commands == [{"command": "pause", "id": "operator"}, {"command": "abort"}]
    assert all("forged" not in m.payload for m in sub.messages())
    status = [m.json()["state"] for m in sub.messages("status")]
    assert status == ["online", "offline"], status
