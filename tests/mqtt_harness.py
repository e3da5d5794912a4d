"""Test harness (for tests and demos): a Mosquitto broker of one's own on a spare port, and
Mosquitto's own clients (mosquitto_sub, mosquitto_pub) to watch and command a fleet, so what a
test sees does not depend on this package's MQTT code."""

from __future__ import annotations

import getpass
import json
import os
import signal
import socket
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tests.waiting import wait_until


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _listening(port: int) -> bool:
    with socket.socket() as s:
        return s.connect_ex(("127.0.0.1", port)) == 0


class Broker:
    """``mosquitto`` on 127.0.0.1:``port`` with persistence in ``workdir`` (sessions and queued
    QoS 1 messages survive :meth:`stop` + :meth:`start`); ``security`` adds config lines."""

    def __init__(self, workdir: Path, *, security: str = "allow_anonymous true\n") -> None:
        workdir.mkdir(parents=True, exist_ok=True)
        self.port = free_port()
        self.workdir = workdir
        self.conf = workdir / "mosquitto.conf"
        self.conf.write_text(
            f"listener {self.port} 127.0.0.1\n"
            f"user {getpass.getuser()}\n"
            f"persistence true\npersistence_location {workdir}/\n"
            f"log_dest file {workdir}/mosquitto.log\n" + security
        )
        self._proc: subprocess.Popen[bytes] | None = None

    def start(self) -> None:
        with (self.workdir / "mosquitto.out").open("ab") as out:
            self._proc = subprocess.Popen(
                ["mosquitto", "-c", str(self.conf)], stdout=out, stderr=subprocess.STDOUT
            )
        wait_until(lambda: _listening(self.port), 10.0, f"a broker on 127.0.0.1:{self.port}")

    def stop(self) -> None:
        """Graceful stop (SIGTERM): the broker saves its sessions."""
        if self._proc is not None and self._proc.poll() is None:
            self._proc.send_signal(signal.SIGTERM)
            self._proc.wait(timeout=10)
        self._proc = None

    def __enter__(self) -> Broker:
        self.start()
        return self

    def __exit__(self, *_: object) -> None:
        self.stop()


@dataclass(frozen=True)
class Message:
    topic: str
    payload: str
    retained: bool

    def json(self) -> Any:
        return json.loads(self.payload)


class Subscriber:
    """``mosquitto_sub`` at QoS 1; every message lands in ``path``. ``persistent``: a
    persistent session (it reconnects by itself, and a broker with persistence keeps its
    messages while it is away, even across a broker restart)."""

    def __init__(
        self,
        port: int,
        topic_filter: str,
        path: Path,
        *,
        user: str | None = None,
        password: str | None = None,
        persistent: bool = False,
    ) -> None:
        self.path = path
        auth = [] if user is None else ["-u", user, "-P", password or ""]
        session = ["-c", "-i", f"test-sub-{port}"] if persistent else []
        with path.open("wb") as out:
            self._proc = subprocess.Popen(
                ["mosquitto_sub", "-h", "127.0.0.1", "-p", str(port), "-q", "1", *session,
                 "-t", topic_filter, "-F", "%r %t %p", *auth],
                stdout=out,
            )  # fmt: skip

    def messages(self, leaf: str | None = None) -> list[Message]:
        """Every complete line so far; ``leaf`` keeps topics ending in /leaf."""
        out = []
        for line in self.path.read_text(encoding="utf-8").splitlines(keepends=True):
            if not line.endswith("\n"):
                break
            retained, topic, payload = line.rstrip("\n").split(" ", 2)
            if leaf is None or topic.endswith("/" + leaf):
                out.append(Message(topic, payload, retained == "1"))
        return out

    def ready(
        self, port: int, topic: str, *, user: str | None = None, password: str | None = None
    ) -> None:
        """Publish probes on ``topic`` until one arrives: the subscription is in place."""
        deadline = time.monotonic() + 10.0
        while time.monotonic() < deadline:
            publish(port, topic, "probe", user=user, password=password)
            time.sleep(0.1)
            if any(m.topic == topic for m in self.messages()):
                return
        raise TimeoutError(f"mosquitto_sub on port {port} never received {topic}")

    def stop(self) -> None:
        self._proc.terminate()
        self._proc.wait(timeout=10)


def publish(
    port: int, topic: str, payload: str, *, user: str | None = None, password: str | None = None
) -> subprocess.CompletedProcess[str]:
    """``mosquitto_pub`` at QoS 1; a refused connection shows in the return code and stderr."""
    auth = [] if user is None else ["-u", user, "-P", password or ""]
    return subprocess.run(
        ["mosquitto_pub", "-h", "127.0.0.1", "-p", str(port), "-q", "1", "-t", topic,
         "-m", payload, *auth],
        capture_output=True, text=True, timeout=20, check=False,
    )  # fmt: skip


def retained_topics(port: int, topic_filter: str, *, remove: bool = False) -> list[str]:
    """Topics under ``topic_filter`` that hold a retained message on the broker at ``port``;
    ``remove``: clear them too, so a test leaves nothing on a user's broker. Mosquitto sends
    retained messages right after the subscription, so a one-second wait sees them all."""
    done = subprocess.run(
        ["mosquitto_sub", "-h", "127.0.0.1", "-p", str(port), "-t", topic_filter,
         "--retained-only", "-W", "1", "-F", "%t",
         *(["--remove-retained"] if remove else [])],
        capture_output=True, text=True, timeout=20, check=False,
    )  # fmt: skip
    return done.stdout.split()


def clear_retained_of_this_run(port: int = 1883) -> list[str]:
    """Clear the retained messages (vehicle status) that this test process's fleets left under
    its own prefixes, ``mdm/test-<pid>-...`` and ``mdm/sitl-<pid>``, on the broker at ``port``;
    returns the topics cleared. Nothing when no broker listens there."""
    with socket.socket() as s:
        if s.connect_ex(("127.0.0.1", port)) != 0:
            return []
    ours = (f"mdm/test-{os.getpid()}-", f"mdm/sitl-{os.getpid()}/")
    topics = [t for t in retained_topics(port, "mdm/#") if t.startswith(ours)]
    for topic in topics:  # an empty retained message deletes the retained one
        subprocess.run(["mosquitto_pub", "-h", "127.0.0.1", "-p", str(port), "-q", "1", "-r",
                        "-n", "-t", topic], capture_output=True, timeout=20, check=False)  # fmt: skip
    return topics
