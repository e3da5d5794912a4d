"""PSO/SPSO/ARPSO peers over MQTT: publish this vehicle's best, keep the last one of each peer.

Topic ``<prefix>/swarm/uav<i>`` (one per vehicle), QoS 0, not retained: a best is only worth
its latest value, and a lost one is what ``policy.swarm.message_drop`` models in the
Monte-Carlo engine. Payload (JSON)::

    {"t": vehicle time s, "best": [north, east], "fitness": f, "current": f_now,
     "known": [[north, east], ...]}

``known`` are the positions of the targets the sender knows to be confirmed (live, a target
has no index: it is where it was confirmed). ``heard(now)`` returns the table that
``mdm_core.search.pso.swarm_best`` takes (one slot per vehicle of the fleet, the own slot
empty), so the decision core never touches the network. The degradation knob of the
Monte-Carlo engine acts on the receiving side: a report is lost with probability ``drop``
(seeded) and used only ``delay`` vehicle seconds after the sender's time stamp (the fleet
shares the emulator's clock). A payload that cannot be read is counted and dropped, never
raised. ``post`` hands the latest report to the sender task (``run``) without waiting.
"""

from __future__ import annotations

import asyncio
import json
import logging
from collections import deque
from dataclasses import dataclass, field

import aiomqtt
import numpy as np

from companion.sensors.detection_payload import MAX_DISTANCE
from companion.telemetry.mqtt.channel import MqttChannel, Received
from mdm_core.search.pso import Best

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class PeerReport:
    """One vehicle's published state."""

    time: float
    best: tuple[float, float]
    fitness: float
    current: float
    known: tuple[tuple[float, float], ...] = field(default=())

    def encode(self) -> bytes:
        return json.dumps(
            {
                "t": self.time,
                "best": list(self.best),
                "fitness": self.fitness,
                "current": self.current,
                "known": [list(k) for k in self.known],
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
                current=float(data["current"]),
                known=tuple((float(n), float(e)) for n, e in data["known"]),
            )
        except (ValueError, TypeError, KeyError) as exc:
            raise ValueError(f"swarm report: {exc!r}") from None
        numbers = [report.time, *report.best, report.fitness, report.current]
        if not np.isfinite([*numbers, *(x for k in report.known for x in k)]).all():
            raise ValueError("swarm report: non-finite number")
        positions = [report.best, *report.known]
        if max(abs(x) for p in positions for x in p) > MAX_DISTANCE:
            raise ValueError(
                f"swarm report: a position more than {MAX_DISTANCE / 1000:g} km from the origin"
            )
        if not 0.0 <= report.fitness <= 1.0 or not 0.0 <= report.current <= 1.0:
            raise ValueError("swarm report: fitness outside [0, 1]")
        return report


class SwarmPeers:
    """The swarm exchange of vehicle ``vehicle`` (0-based) of a fleet of ``vehicles``."""

    def __init__(
        self,
        channel: MqttChannel,
        prefix: str,
        vehicle: int,
        vehicles: int,
        *,
        delay: float = 0.0,
        drop: float = 0.0,
        seed: int = 0,
    ) -> None:
        if not 0 <= vehicle < vehicles:
            raise ValueError(f"vehicle {vehicle} outside a fleet of {vehicles}")
        if not delay >= 0:
            raise ValueError(f"swarm message delay must be >= 0 s, got {delay}")
        if not 0 <= drop <= 1:
            raise ValueError(f"swarm message drop must be in [0, 1], got {drop}")
        self._channel = channel
        self._prefix = prefix
        self.vehicle = vehicle
        self.vehicles = vehicles
        self.delay = delay
        self.drop = drop
        self._rng = np.random.default_rng([seed, vehicle])
        self._waiting: dict[int, deque[PeerReport]] = {}
        self._last: dict[int, PeerReport] = {}
        self._outgoing: PeerReport | None = None
        self._ready = asyncio.Event()
        self.received = 0
        """Peer reports that arrived (before the drop)."""
        self.dropped = 0
        """Of those, lost by the ``drop`` draw."""
        self.rejected = 0
        """Payloads that could not be read (or named a vehicle outside the fleet)."""
        self.sent = 0
        channel.subscribe(f"{prefix}/swarm/+", self._on_message, qos=0)

    def topic(self, vehicle: int) -> str:
        return f"{self._prefix}/swarm/uav{vehicle}"

    async def publish(self, report: PeerReport) -> None:
        """Send this vehicle's report (raises MqttError when the link is down)."""
        await self._channel.publish(self.topic(self.vehicle), report.encode(), qos=0)
        self.sent += 1

    def post(
        self,
        time: float,
        best: tuple[float, float],
        fitness: float,
        current: float,
        known: list[tuple[float, float]],
    ) -> None:
        """Queue this vehicle's report for ``run``; a newer one replaces one not yet sent."""
        self._outgoing = PeerReport(time, best, fitness, current, tuple(known))
        self._ready.set()

    async def run(self) -> None:
        """Send what ``post`` queued, latest first; a report that finds the link down is lost
        (QoS 0, as a lost message in the engine)."""
        while True:
            await self._ready.wait()
            self._ready.clear()
            await self.flush()

    async def flush(self) -> None:
        """Send the report ``post`` queued, if any (the last one, at the end of a mission)."""
        report, self._outgoing = self._outgoing, None
        if report is None or not self._channel.connected.is_set():
            return
        try:
            await self.publish(report)
        except aiomqtt.MqttError as exc:
            log.debug("swarm report not sent: %s", exc)

    def heard(self, now: float) -> tuple[Best, np.ndarray]:
        """Last best and current fitness of every vehicle usable at vehicle time ``now``: Best
        of shape (1, vehicles) and (1, vehicles); slots never heard from (and the own slot)
        have fitness 0."""
        for sender, waiting in self._waiting.items():
            while waiting and waiting[0].time + self.delay <= now:
                self._last[sender] = waiting.popleft()
        n = self.vehicles
        best = Best(np.zeros((1, n, 2)), np.zeros((1, n)), np.full((1, n), -1, dtype=np.intp))
        current = np.zeros((1, n))
        for j, report in self._last.items():
            best.position[0, j] = report.best
            best.fitness[0, j] = report.fitness
            current[0, j] = report.current
        return best, current

    def known(self) -> list[tuple[float, float]]:
        """Positions of targets the reports in use say are confirmed (call after ``heard``)."""
        return [k for r in self._last.values() for k in r.known]

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
        self.received += 1
        if self._rng.random() < self.drop:
            self.dropped += 1
            return
        waiting = self._waiting.setdefault(sender, deque())
        newest = waiting[-1] if waiting else self._last.get(sender)
        if newest is None or report.time >= newest.time:
            waiting.append(report)
