"""docker/compose.yaml for real: the image built from a local Debian base, then broker (ACL and
password file), signed emulator and 3 companions brought up to a completed mission; the results
and the MQTT events are read from the host, and `down -v` leaves nothing behind.

Skipped only where no Docker engine (or no Compose v2) answers; `.ci/run` installs both."""

from __future__ import annotations

import os
import secrets
import subprocess
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from companion.fleet.scoring import score
from companion.telemetry import read_records
from mdm_profiles import load_profile
from tests.docker import engine
from tests.docker.engine import ROOT, docker
from tests.mqtt_harness import Subscriber, free_port, publish, wait_until

COMPOSE = ROOT / "docker" / "compose.yaml"
IMAGE = "mdm-search:latest"
BROKER_IMAGE = "mdm-mosquitto:local"
VEHICLES = 3
COMPANIONS = [f"companion-{i}" for i in range(VEHICLES)]
SPEEDUP = "50"
"""Sim/wall ratio: the profile's 1000 s search and the flight home in well under a minute."""
MISSION_WALL_S = 240.0
COMPANION_UID, BROKER_UID = 10001, 1883
"""Who reads the secrets in the containers (docker/Dockerfile, compose.yaml's broker user)."""

reason = engine.missing_engine()
pytestmark = pytest.mark.skipif(reason is not None, reason=reason or "")


def _timed(what: str, *args: str) -> None:
    start = time.monotonic()
    docker(*args)
    print(f"{what}: {time.monotonic() - start:.1f} s")


@dataclass
class Stack:
    """One compose project of docker/compose.yaml, with its settings in ``env``."""

    project: str
    env: dict[str, str]
    passwords: dict[str, str]
    port: int

    def compose(self, *args: str, timeout: float = 600.0) -> subprocess.CompletedProcess[str]:
        return docker("compose", "-p", self.project, "-f", str(COMPOSE), *args,
                      timeout=timeout, env=self.env)  # fmt: skip


@pytest.fixture(scope="module")
def images(tmp_path_factory: pytest.TempPathFactory) -> None:
    """mdm-search and the Debian-packaged broker, built on the local Debian base."""
    start = time.monotonic()
    base = engine.ensure_base_image()
    print(f"base image {base}: {time.monotonic() - start:.1f} s")
    _timed("broker image", "build", "--network=host", "--build-arg", f"BASE={base}",
           "-t", BROKER_IMAGE, str(ROOT / "docker" / "mosquitto"))  # fmt: skip
    wheels = tmp_path_factory.mktemp("wheels")
    start = time.monotonic()
    engine.build_wheels(wheels)
    print(f"wheels: {time.monotonic() - start:.1f} s")
    with engine.serve_dir(wheels) as url:
        _timed("mdm-search image", "build", "--network=host", "--build-arg", f"BASE={base}",
               "--build-arg", "PIP_NO_INDEX=1", "--build-arg", f"PIP_FIND_LINKS={url}",
               "-f", str(ROOT / "docker" / "Dockerfile"), "-t", IMAGE, str(ROOT))  # fmt: skip
    # the image this build replaced (and the build stage it came from) would pile up run by run
    docker("image", "prune", "-f", "--filter", "label=org.opencontainers.image.title=mdm-search")
    size = int(docker("image", "inspect", "-f", "{{.Size}}", IMAGE).stdout)
    print(f"mdm-search image: {size / 1e6:.0f} MB")


def _secrets(folder: Path) -> dict[str, str]:
    """The files compose.yaml reads from $MDM_SECRETS, made as docker/mosquitto/README.md says;
    returns the operator's and the companions' MQTT passwords."""
    folder.mkdir()
    passwords = {user: secrets.token_hex(16) for user in ["operator", "monitor",
                                                          *(f"uav{i}" for i in range(VEHICLES))]}  # fmt: skip
    (folder / "mavlink.key").write_text(secrets.token_hex(32) + "\n")
    passwd = folder / "mosquitto.passwd"
    for n, (user, password) in enumerate(passwords.items()):
        create = ["-c"] if n == 0 else []
        subprocess.run(["mosquitto_passwd", *create, "-b", str(passwd), user, password],
                       check=True, timeout=30)  # fmt: skip
        if user.startswith("uav"):
            (folder / f"{user}.pw").write_text(password + "\n")
    for path in folder.iterdir():
        owner = BROKER_UID if path == passwd else COMPANION_UID
        if os.geteuid() == 0:
            os.chown(path, owner, owner)
            path.chmod(0o600)
        else:  # the owners cannot be given: readable by all, in a private temporary folder
            path.chmod(0o644)
    return passwords


@pytest.fixture
def stack(images: None, tmp_path: Path) -> Iterator[Stack]:
    """A compose project of its own; at the end `down -v`, then nothing of the project may be
    left: no container, network or volume."""
    port = free_port()
    env = {**os.environ, "MDM_SECRETS": str(tmp_path / "secrets"), "MDM_MQTT_PORT": str(port),
           "MDM_MOSQUITTO_IMAGE": BROKER_IMAGE, "MDM_SPEEDUP": SPEEDUP}  # fmt: skip
    stack = Stack(f"mdm-test-{os.getpid()}", env, _secrets(tmp_path / "secrets"), port)
    try:
        yield stack
    finally:
        logs = stack.compose("logs", "--no-color").stdout
        (tmp_path / "compose.log").write_text(logs)
        start = time.monotonic()
        stack.compose("down", "-v", "--remove-orphans", "--timeout", "10")
        print(f"down -v: {time.monotonic() - start:.1f} s")
        label = f"label=com.docker.compose.project={stack.project}"
        for kind in (["ps", "-a"], ["network", "ls"], ["volume", "ls"]):
            left = docker(*kind, "-q", "--filter", label).stdout.split()
            assert not left, f"`docker {' '.join(kind)}` after down -v: {left}"
        print("docker ps -a:\n" + docker("ps", "-a").stdout)
        print("docker volume ls:\n" + docker("volume", "ls").stdout)


def _broker_ready(port: int, password: str) -> None:
    wait_until(lambda: publish(port, "mdm/probe/ready/cmd", "probe", user="operator",
                               password=password).returncode == 0,
               30.0, f"the broker on 127.0.0.1:{port} accepting the operator")  # fmt: skip


def _mqtt_events(sub: Subscriber, vehicle: int) -> list[dict[str, object]]:
    """The vehicle's events as the broker delivered them, each seq once, in seq order."""
    by_seq = {}
    for message in sub.messages("event"):
        if message.topic == f"mdm/paper-fixed/uav{vehicle}/event":
            event = message.json()
            by_seq[event["seq"]] = event
    return [by_seq[k] for k in sorted(by_seq)]


def _all_events(sub: Subscriber, vehicle: int, count: int) -> list[dict[str, object]]:
    """The vehicle's events once ``count`` of them reached the subscriber (QoS 1: they may
    still be on their way when the companion has exited)."""
    wait_until(lambda: len(_mqtt_events(sub, vehicle)) >= count, 20.0,
               f"uav{vehicle}'s {count} events on the broker")  # fmt: skip
    return _mqtt_events(sub, vehicle)


def _logged_events(runs: Path, vehicle: int) -> list[dict[str, object]]:
    return [r for r in read_records(runs / f"mission-{vehicle}.jsonl") if r["event"] != "tick"]


@pytest.mark.timeout(900)
def test_compose_flies_a_signed_mission_with_events_on_the_broker(
    stack: Stack, tmp_path: Path
) -> None:
    passwords, port = stack.passwords, stack.port
    stack.compose("up", "-d", "mosquitto")
    _broker_ready(port, passwords["operator"])
    # the ACL and the password file are the broker's: a wrong password and a companion's
    # account (which may not command) are refused, the operator is not
    wrong = publish(port, "mdm/paper-fixed/uav0/cmd", "{}", user="operator", password="wrong")
    assert wrong.returncode != 0, "the broker took a wrong password"
    sub = Subscriber(port, "mdm/#", tmp_path / "mqtt.txt", user="monitor",
                     password=passwords["monitor"])  # fmt: skip
    spy = Subscriber(port, "mdm/+/+/cmd", tmp_path / "cmd.txt", user="operator",
                     password=passwords["operator"])  # fmt: skip
    try:
        for probe, who in (("sub", sub), ("spy", spy)):
            who.ready(port, f"mdm/probe/{probe}/cmd", user="operator",
                      password=passwords["operator"])  # fmt: skip
        publish(port, "mdm/paper-fixed/uav1/cmd", '{"command": "abort"}', user="uav0",
                password=passwords["uav0"])  # fmt: skip
        start = time.monotonic()
        stack.compose("up", "-d")
        ids = stack.compose("ps", "-aq", *COMPANIONS).stdout.split()
        assert len(ids) == VEHICLES
        codes = docker("wait", *ids, timeout=MISSION_WALL_S).stdout.split()
        print(f"mission (up to the last companion's exit): {time.monotonic() - start:.1f} s")
        assert codes == ["0"] * VEHICLES, f"companion exit codes {codes}"
        assert all(m.topic.startswith("mdm/probe/") for m in spy.messages()), (
            "a companion's account published a command"
        )
        runs = tmp_path / "runs"
        stack.compose("cp", "companion-0:/home/mdm/runs", str(runs))
        profile = load_profile("paper-fixed")
        result = score(profile, runs, VEHICLES, profile.mission.duration)
        print(f"T_nc {result.tnc} of {len(profile.targets)} in {profile.mission.duration:.0f} s "
              f"by {VEHICLES} vehicles; confirmations {len(result.confirmations)}, false "
              f"{result.false_confirmations}; end {result.end_reasons}")  # fmt: skip
        assert result.end_reasons == dict.fromkeys(range(VEHICLES), "mission time")
        assert result.false_confirmations == 0
        assert "MAVLink signing on" in stack.compose("logs", "emulator").stdout
        assert any(read_records(runs / "emulator-events.jsonl")), "the emulator logged nothing"
        for i in range(VEHICLES):
            logged = _logged_events(runs, i)
            events = _all_events(sub, i, len(logged))
            assert [e["seq"] for e in events] == list(range(len(logged)))
            published = [{k: v for k, v in e.items() if k != "seq"} for e in events]
            assert published == [{**r, "vehicle": i} for r in logged], f"uav{i}: MQTT != log"
            states = [m.json() for m in sub.messages("state") if f"/uav{i}/" in m.topic]
            assert {s["phase"] for s in states} >= {"search", "return"}, f"uav{i} states"
    finally:
        sub.stop()
        spy.stop()
