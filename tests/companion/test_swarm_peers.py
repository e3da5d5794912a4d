"""Swarm bests exchanged through a real Mosquitto broker feed the PSO core's swarm_best."""

from __future__ import annotations

import asyncio
import json
from collections.abc import Callable

import numpy as np
import pytest

from companion.telemetry.mqtt.channel import MqttChannel
from companion.telemetry.mqtt.settings import MqttSettings
from companion.telemetry.mqtt.swarm_peers import PeerReport, SwarmPeers
from mdm_core.search.pso import Best, swarm_best
from tests.mqtt_harness import Broker, publish
from tests.waiting import wait_until_async

PREFIX = "mdm/test"


@pytest.mark.asyncio
async def test_a_peer_best_reaches_the_other_vehicle_and_wins_swarm_best(
    mosquitto: Callable[..., Broker],
) -> None:
    with mosquitto() as broker:
        await _exchange(broker.port)


async def _exchange(port: int) -> None:
    settings = MqttSettings(host="127.0.0.1", port=port)
    channels = [MqttChannel(settings, client_id=f"swarm-{i}") for i in range(2)]
    peers = [SwarmPeers(c, PREFIX, i, 3) for i, c in enumerate(channels)]
    tasks = [asyncio.create_task(c.run()) for c in channels]
    try:
        await asyncio.wait_for(asyncio.gather(*(c.connected.wait() for c in channels)), 10)
        report = PeerReport(12.0, (5000.0, 4200.0), 0.8, 0.5, ((700.0, 650.5),))
        # Resend until it arrives: the subscription may not be in place at the first send.
        while peers[1].heard(12.0)[0].fitness[0, 0] == 0:
            await peers[0].publish(report)
            await asyncio.sleep(0.05)
        heard, current = peers[1].heard(12.0)
        assert heard.position[0, 0].tolist() == [5000.0, 4200.0]
        assert heard.source[0].tolist() == [-1, -1, -1]
        assert current[0].tolist() == [0.5, 0.0, 0.0]
        assert peers[1].known() == [(700.0, 650.5)]
        # The sender does not hear itself.
        assert peers[0].heard(12.0)[0].fitness.sum() == 0

        own = Best(np.array([[0.0, 0.0]]), np.array([0.3]), np.array([0]))
        links = np.array([[True, False, True]])
        best, mine = swarm_best(own, heard, links)
        assert best.position[0].tolist() == [5000.0, 4200.0]
        assert not mine[0]

        # An older report does not replace a newer one: the garbage sent after it on the same
        # connection arrives after it, so once that is counted the old report was handled.
        await peers[0].publish(PeerReport(5.0, (1.0, 1.0), 0.9, 0.9))
        await channels[0].publish(f"{PREFIX}/swarm/uav0", b"not json")
        await wait_until_async(
            lambda: peers[1].rejected, 10.0, "one rejected message", until=lambda n: n == 1
        )
        assert peers[1].heard(20.0)[0].fitness[0, 0] == 0.8
        # A vehicle outside the fleet is counted and dropped, not raised.
        await asyncio.to_thread(publish, port, f"{PREFIX}/swarm/uav7", report.encode().decode())
        await wait_until_async(
            lambda: peers[1].rejected, 10.0, "two rejected messages", until=lambda n: n == 2
        )
    finally:
        for t in tasks:
            t.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)


@pytest.mark.asyncio
async def test_delay_holds_a_report_back_and_drop_one_loses_every_report(
    mosquitto: Callable[..., Broker],
) -> None:
    with mosquitto() as broker:
        await _degraded(broker.port)


async def _degraded(port: int) -> None:
    settings = MqttSettings(host="127.0.0.1", port=port)
    channels = [MqttChannel(settings, client_id=f"swarm-deg-{i}") for i in range(3)]
    sender = SwarmPeers(channels[0], PREFIX, 0, 3)
    late = SwarmPeers(channels[1], PREFIX, 1, 3, delay=30.0)
    deaf = SwarmPeers(channels[2], PREFIX, 2, 3, drop=1.0)
    tasks = [asyncio.create_task(c.run()) for c in channels]
    tasks.append(asyncio.create_task(sender.run()))
    try:
        await asyncio.wait_for(asyncio.gather(*(c.connected.wait() for c in channels)), 10)
        while late.received == 0 or deaf.received == 0:
            sender.post(100.0, (10.0, 20.0), 0.6, 0.6, [])
            await asyncio.sleep(0.05)
        assert sender.sent >= 1
        # Sent at vehicle time 100 s with a 30 s delay: not usable before 130 s.
        assert late.heard(129.9)[0].fitness[0, 0] == 0
        assert late.heard(130.0)[0].fitness[0, 0] == 0.6
        assert deaf.dropped == deaf.received
        assert deaf.heard(1e9)[0].fitness.sum() == 0
    finally:
        for t in tasks:
            t.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)


@pytest.mark.parametrize(
    ("field", "value", "fault"),
    [
        ("best", [float("nan"), 0.0], "non-finite"),
        ("best", [3.0e5, 0.0], "200 km"),
        ("known", [[0.0, -2.5e5]], "200 km"),
        ("fitness", 1.5, "fitness outside"),
    ],
)
def test_a_peer_report_out_of_range_is_refused_naming_the_fault(
    field: str, value: object, fault: str
) -> None:
    good = {"t": 1.0, "best": [10.0, 20.0], "fitness": 0.5, "current": 0.2, "known": []}
    assert PeerReport.decode(json.dumps(good).encode()).best == (10.0, 20.0)
    with pytest.raises(ValueError, match=fault):
        PeerReport.decode(json.dumps({**good, field: value}).encode())
