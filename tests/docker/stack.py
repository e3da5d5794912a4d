"""One compose project of docker/'s files under test: its secrets made as the docs say, its
settings in the environment, and after `down -v` the check that nothing of it is left."""

from __future__ import annotations

import os
import secrets
import subprocess
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from tests.docker.engine import ROOT, docker
from tests.mqtt_harness import Subscriber, publish
from tests.waiting import wait_until

BROKER_IMAGE = "mdm-mosquitto:local"
COMPANION_UID, BROKER_UID = 10001, 1883
"""Who reads the secrets in the containers (docker/Dockerfile, the compose files' broker)."""


@dataclass
class Stack:
    """``docker compose -p PROJECT -f FILE`` with the settings in ``env``."""

    file: Path
    project: str
    env: dict[str, str]
    passwords: dict[str, str]
    port: int
    subscribers: list[Subscriber] = field(default_factory=list)
    """Ended with the project."""

    def compose(self, *args: str, timeout: float = 600.0) -> subprocess.CompletedProcess[str]:
        return docker("compose", "-p", self.project, "-f", str(self.file), *args,
                      timeout=timeout, env=self.env)  # fmt: skip

    def broker_ready(self) -> None:
        """The broker accepts the operator (its port is published before it listens)."""
        wait_until(
            lambda: (
                publish(
                    self.port,
                    "mdm/probe/ready/cmd",
                    "probe",
                    user="operator",
                    password=self.passwords["operator"],
                ).returncode
                == 0
            ),
            30.0,
            f"the broker on 127.0.0.1:{self.port} accepting the operator",
        )

    def subscriber(self, topic_filter: str, path: Path, user: str) -> Subscriber:
        """``mosquitto_sub`` as ``user`` on the host, subscribed once this returns."""
        sub = Subscriber(self.port, topic_filter, path, user=user, password=self.passwords[user])
        self.subscribers.append(sub)
        sub.ready(
            self.port,
            f"mdm/probe/{path.stem}/cmd",
            user="operator",
            password=self.passwords["operator"],
        )
        return sub

    def wait_exit(self, services: list[str], timeout: float) -> list[str]:
        """The exit codes of ``services``' containers once all have exited."""
        ids = self.compose("ps", "-aq", *services).stdout.split()
        assert len(ids) == len(services), f"containers of {services}: {ids}"
        return docker("wait", *ids, timeout=timeout).stdout.split()


def make_secrets(folder: Path, vehicles: list[int]) -> dict[str, str]:
    """The files the compose files read from $MDM_SECRETS, made as docker/mosquitto/README.md
    and README.md say; returns every account's MQTT password."""
    folder.mkdir()
    users = ["operator", "monitor", *(f"uav{i}" for i in vehicles)]
    passwords = {user: secrets.token_hex(16) for user in users}
    (folder / "mavlink.key").write_text(secrets.token_hex(32) + "\n")
    passwd = folder / "mosquitto.passwd"
    for n, (user, password) in enumerate(passwords.items()):
        create = ["-c"] if n == 0 else []
        subprocess.run(
            ["mosquitto_passwd", *create, "-b", str(passwd), user, password], check=True, timeout=30
        )
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


@contextmanager
def project(
    file: str, tmp_path: Path, vehicles: list[int], port: int, settings: dict[str, str]
) -> Iterator[Stack]:
    """A compose project of its own for ``docker/FILE``; at the end `down -v`, then nothing of
    the project may be left: no container, network or volume."""
    env = {
        **os.environ,
        "MDM_SECRETS": str(tmp_path / "secrets"),
        "MDM_MQTT_PORT": str(port),
        "MDM_MOSQUITTO_IMAGE": BROKER_IMAGE,
        **settings,
    }
    name = f"mdm-test-{Path(file).stem.replace('.', '-')}-{os.getpid()}"
    stack = Stack(
        ROOT / "docker" / file, name, env, make_secrets(tmp_path / "secrets", vehicles), port
    )
    try:
        yield stack
    finally:
        for sub in stack.subscribers:
            sub.stop()
        (tmp_path / "compose.log").write_text(stack.compose("logs", "--no-color").stdout)
        start = time.monotonic()
        stack.compose("down", "-v", "--remove-orphans", "--timeout", "10")
        print(f"down -v: {time.monotonic() - start:.1f} s")
        label = f"label=com.docker.compose.project={name}"
        for kind in (["ps", "-a"], ["network", "ls"], ["volume", "ls"]):
            left = docker(*kind, "-q", "--filter", label).stdout.split()
            assert not left, f"`docker {' '.join(kind)}` after down -v: {left}"
        print("docker ps -a:\n" + docker("ps", "-a").stdout)
        print("docker volume ls:\n" + docker("volume", "ls").stdout)


def mqtt_events(sub: Subscriber, topic: str) -> list[dict[str, object]]:
    """The events the broker delivered on ``topic``, each seq once, in seq order."""
    by_seq = {}
    for message in sub.messages("event"):
        if message.topic == topic:
            event = message.json()
            by_seq[event["seq"]] = event
    return [by_seq[k] for k in sorted(by_seq)]


def all_events(sub: Subscriber, topic: str, count: int) -> list[dict[str, object]]:
    """The events on ``topic`` once ``count`` of them reached the subscriber (QoS 1: they may
    still be on their way when the companion has exited)."""
    wait_until(lambda: len(mqtt_events(sub, topic)) >= count, 20.0, f"{count} events on {topic}")
    return mqtt_events(sub, topic)
