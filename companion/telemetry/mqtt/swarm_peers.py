"""PSO/SPSO/ARPSO peers over MQTT: publish this vehicle's best, keep the last one of each peer.

Topic ``<prefix>/swarm/uav<i>`` (one per vehicle), QoS 0, not retained: a best is only worth
its latest value, and a lost one is what ``policy.swarm.message_drop`` models in the
Monte-Carlo engine. Payload (JSON)::

    {"t": vehicle time s, "best": [north, east], "fitness": f, "source": k,
     "current": f_now, "known": [k, ...]}

``heard()`` returns the table that ``companion.search.pso.swarm_best`` takes (one slot per
vehicle of the fleet, the own slot empty), so the decision core never touches the network.
A payload that cannot be read is counted and dropped, never raised.
"""

from __future__ import annotations

import json
import logging
from dataclasses import dataclass

import numpy as np

from companion.search.pso import Best
from companion.telemetry.mqtt.channel import MqttChannel, Received

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class PeerReport:
    """One vehicle's published state."""

    time: float
    best: tuple[float, float]
    fitness: float
    source: int
    current: float
    known: frozenset[int]

    def encode(self) -> bytes:
        return json.dumps(
            {
                "t": self.time,
                "best": list(self.best),
                "fitness": self.fitness,
                "source": self.source,
                "current": self.current,
                "known": sorted(self.known),
            }
        ).encode()

    @classmethod
    def decode(cls, payload: bytes) -> PeerReport:
        """Parse a payload; ValueError naming what is wrong."""
        try:
            data = json.loads(payload)
            north, east = (float(v) for v in data["best"])
            report = cls(
                time=float(data["t"]),
                best=(north, east),
                fitness=float(data["fitness"]),
                source=int(data["source"]),
                current=float(data["current"]),
                known=frozenset(int(k) for k in data["known"]),
            )
        except (ValueError, TypeError, KeyError) as exc:
            raise ValueError(f"swarm report: {exc!r}") from None
        if not (np.isfinite([report.time, *report.best, report.fitness, report.current]).all()):
            raise ValueError("swarm report: non-finite number")
        if not 0.0 <= report.fitness <= 1.0 or not 0.0 <= report.current <= 1.0:
            raise ValueError("swarm report: fitness outside [0, 1]")
        return report


class SwarmPeers:
    """The swarm exchange of vehicle ``vehicle`` (0-based) of a fleet of ``vehicles``."""

    def __init__(self, channel: MqttChannel, prefix: str, vehicle: int, vehicles: int) -> None:
        if not 0 <= vehicle < vehicles:
            raise ValueError(f"vehicle {vehicle} outside a fleet of {vehicles}")
        self._channel = channel
        self._prefix = prefix
        self.vehicle = vehicle
        self.vehicles = vehicles
        self._last: dict[int, PeerReport] = {}
        self.rejected = 0
        """Payloads that could not be read (or named a vehicle outside the fleet)."""
        channel.subscribe(f"{prefix}/swarm/+", self._on_message, qos=0)

    def topic(self, vehicle: int) -> str:
        return f"{self._prefix}/swarm/uav{vehicle}"

    async def publish(self, report: PeerReport) -> None:
        """Send this vehicle's report (raises MqttError when the link is down)."""
        await self._channel.publish(self.topic(self.vehicle), report.encode(), qos=0)

    def heard(self) -> tuple[Best, np.ndarray]:
        """Last best and current fitness heard from every vehicle: Best of shape (1, vehicles)
        and (1, vehicles); slots never heard from (and the own slot) have fitness 0."""
        n = self.vehicles
        best = Best(np.zeros((1, n, 2)), np.zeros((1, n)), np.full((1, n), -1, dtype=np.intp))
        current = np.zeros((1, n))
        for j, report in self._last.items():
            best.position[0, j] = report.best
            best.fitness[0, j] = report.fitness
            best.source[0, j] = report.source
            current[0, j] = report.current
        return best, current

    def known(self) -> frozenset[int]:
        """Targets some peer reported confirmed."""
        return frozenset().union(*(r.known for r in self._last.values()))

    def _on_message(self, message: Received) -> None:
        leaf = message.topic.rsplit("/", 1)[-1]
        try:
            sender = int(leaf.removeprefix("uav"))
            if not (leaf.startswith("uav") and 0 <= sender < self.vehicles):
                raise ValueError(f"no vehicle {leaf!r} in a fleet of {self.vehicles}")
            report = PeerReport.decode(message.payload)
        except ValueError as exc:
            self.rejected += 1
            log.warning("swarm peer message on %s dropped: %s", message.topic, exc)
            return
        if sender == self.vehicle:
            return
        last = self._last.get(sender)
        if last is None or report.time >= last.time:
            self._last[sender] = report
