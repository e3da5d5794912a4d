"""The embedded broker keeps the rules Mosquitto keeps: the same probes (connections refused,
publishes dropped, deliveries read-checked live and retained, a last will on another's topic)
against Mosquitto 2 with docker/mosquitto/acl and against the embedded broker with the packaged
copy, both reading one password file written by mdm_ground.broker, give the same messages to
every subscriber; and the expected ones (the test is not satisfied by two brokers that both
deliver nothing)."""

from __future__ import annotations

import asyncio
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from mdm_ground.broker.accounts import Accounts, create_accounts
from mdm_ground.broker.embedded import PROJECT_ACL, EmbeddedBroker
from tests.mqtt_harness import Broker, Subscriber, publish

ACL = Path(__file__).resolve().parents[3] / "docker" / "mosquitto" / "acl"
M = "mdm/rules"
Observed = dict[str, object]


@contextmanager
def _embedded(passwd: Path) -> Iterator[int]:
    """The embedded broker in a thread of its own (the probes are blocking clients); its port."""
    started: list[tuple[int, asyncio.AbstractEventLoop, asyncio.Event]] = []
    ready = threading.Event()

    async def serve() -> None:
        async with EmbeddedBroker("127.0.0.1", 0, password_file=passwd) as broker:
            stop = asyncio.Event()
            started.append((broker.port, asyncio.get_running_loop(), stop))
            ready.set()
            await stop.wait()

    thread = threading.Thread(target=asyncio.run, args=(serve(),), daemon=True)
    thread.start()
    assert ready.wait(20), "the embedded broker did not start"
    port, loop, stop = started[0]
    try:
        yield port
    finally:
        loop.call_soon_threadsafe(stop.set)
        thread.join(20)


def _will_client(port: int, acc: Accounts, user: str, topic: str, payload: str) -> None:
    """A client of ``user`` with a retained QoS 1 will on ``topic``, killed (no DISCONNECT):
    the broker publishes the will, if the ACL lets it."""
    proc = subprocess.Popen(
        ["mosquitto_sub", "-h", "127.0.0.1", "-p", str(port), "-u", user, "-P", acc.password(user),
         "-t", f"{M}/{user}/cmd", "--will-topic", topic, "--will-payload", payload,
         "--will-qos", "1", "--will-retain"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    time.sleep(0.5)
    proc.send_signal(signal.SIGKILL)
    proc.wait(10)


def _probe(port: int, acc: Accounts, tmp: Path) -> Observed:
    """Every probe on the broker at ``port``: refusals (exit codes) and what each of five
    subscribers received ("retained topic payload" lines, sorted)."""

    def pub(
        user: str | None,
        topic: str,
        payload: str,
        password: str | None = None,
        *,
        retain: bool = False,
    ) -> int:
        given = None if user is None else (password or acc.password(user))
        if not retain:
            return publish(port, topic, payload, user=user, password=given).returncode
        assert user is not None
        assert given is not None
        return subprocess.run(["mosquitto_pub", "-h", "127.0.0.1", "-p", str(port), "-u", user,
                               "-P", given, "-q", "1", "-r", "-t", topic, "-m", payload],
                              timeout=20, check=False).returncode  # fmt: skip

    observed: Observed = {}
    # retained before anyone subscribes: delivered on subscription, if readable
    observed["retained uav1 status"] = pub("uav1", f"{M}/uav1/status", "uav1-online", retain=True)
    observed["retained uav1 cmd"] = pub("operator", f"{M}/uav1/cmd", "retained-cmd", retain=True)
    tmp.mkdir(parents=True)
    subscribers = {
        f"{who} {flt}": Subscriber(port, flt, tmp / f"sub-{n}.txt", user=who,
                                   password=acc.password(who))
        for n, (who, flt) in enumerate([("uav0", "mdm/#"), ("uav0", f"{M}/uav1/status"), ("operator", "mdm/#"),
                         ("monitor", "mdm/#"), ("uav1", f"{M}/+/cmd")])
    }  # fmt: skip
    try:
        time.sleep(1.0)
        observed["anonymous"] = pub(None, f"{M}/uav0/cmd", "anonymous-cmd")
        observed["wrong password"] = pub("operator", f"{M}/uav0/cmd", "guess-cmd", "guess")
        observed["unknown user"] = pub("nobody", f"{M}/uav0/cmd", "nobody-cmd", "x")
        for user, leaf, label in [
            ("operator", "uav0/cmd", "op-cmd-uav0"),
            ("operator", "all/cmd", "op-cmd-all"),
            ("uav1", "uav0/cmd", "uav1-forged-cmd"),
            ("uav0", "uav0/cmd", "uav0-own-cmd"),
            ("uav1", "uav0/state", "uav1-forged-state"),
            ("uav1", "uav1/state", "uav1-state"),
            ("uav1", "uav1/event", "uav1-event"),
            ("uav0", "uav0/detections", "uav0-detection"),
            ("uav1", "uav0/detections", "uav1-forged-detection"),
            ("monitor", "uav0/cmd", "monitor-cmd"),
            ("operator", "uav0/state", "op-forged-state"),
        ]:
            observed[f"{user} -> {leaf}"] = pub(user, f"{M}/{leaf}", label)
        _will_client(port, acc, "uav1", f"{M}/uav0/status", "uav1-forged-will")
        _will_client(port, acc, "uav1", f"{M}/uav1/status", "uav1-own-will")
        time.sleep(1.5)
    finally:
        for s in subscribers.values():
            s.stop()
    for name, s in subscribers.items():
        observed[name] = sorted(f"{int(m.retained)} {m.topic} {m.payload}" for m in s.messages())
    return observed


def test_packaged_acl_is_docker_mosquittos() -> None:
    assert PROJECT_ACL.read_bytes() == ACL.read_bytes()


@pytest.mark.timeout(180)
def test_embedded_broker_delivers_and_refuses_exactly_what_mosquitto_does(
    mosquitto: Callable[..., Broker], tmp_path: Path
) -> None:
    acc = create_accounts(tmp_path / "accounts", vehicles=2)
    real = mosquitto(
        security=f"allow_anonymous false\npassword_file {acc.passwd}\nacl_file {ACL}\n"
    )
    real.start()
    try:
        by_mosquitto = _probe(real.port, acc, tmp_path / "mosquitto")
    finally:
        real.stop()
    with _embedded(acc.passwd) as port:
        by_embedded = _probe(port, acc, tmp_path / "embedded")
    assert by_embedded == by_mosquitto
    # what both did, spelled out
    assert [by_mosquitto[k] != 0 for k in ("anonymous", "wrong password", "unknown user")] == [
        True, True, True,
    ]  # fmt: skip
    assert by_mosquitto["uav0 mdm/#"] == [
        f"0 {M}/all/cmd op-cmd-all",
        f"0 {M}/uav0/cmd op-cmd-uav0",
        f"0 {M}/uav0/detections uav0-detection",
    ]
    assert by_mosquitto["uav0 mdm/rules/uav1/status"] == []
    assert by_mosquitto["operator mdm/#"] == sorted([
        f"0 {M}/uav0/cmd op-cmd-uav0", f"0 {M}/all/cmd op-cmd-all", f"0 {M}/uav1/state uav1-state",
        f"0 {M}/uav1/event uav1-event", f"0 {M}/uav0/detections uav0-detection",
        f"0 {M}/uav1/status uav1-own-will", f"1 {M}/uav1/status uav1-online",
        f"1 {M}/uav1/cmd retained-cmd",
    ])  # fmt: skip
    assert by_mosquitto["monitor mdm/#"] == by_mosquitto["operator mdm/#"]
    assert by_mosquitto["uav1 mdm/rules/+/cmd"] == sorted(
        [f"0 {M}/all/cmd op-cmd-all", f"1 {M}/uav1/cmd retained-cmd"]
    )
