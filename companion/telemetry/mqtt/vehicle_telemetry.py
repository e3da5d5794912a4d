"""A companion's MQTT side: events through the durable outbox (QoS 1, in order), state at a
rate, a retained online/offline status with a last will, and operator commands in.

It runs beside the mission as tasks of its own (``vI-mqtt-connection``, ``-events``,
``-state``), never inside the mission's TaskGroup: whatever happens to the broker or to this
code, the vehicle keeps flying. ``emit`` (the EventSink side, called by the decision loop) only
appends to a file and a queue.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import json
import logging
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import aiomqtt

from companion.telemetry.mqtt.channel import MqttChannel, Received
from companion.telemetry.mqtt.commands import CommandError, Operated, obey, parse_command
from companion.telemetry.mqtt.outbox import EventOutbox
from companion.telemetry.mqtt.settings import MqttSettings, settings_for
from companion.telemetry.mqtt.topics import VehicleTopics, default_prefix
from mdm_profiles.mqtt_spec import MqttSpec

log = logging.getLogger(__name__)

NOT_PUBLISHED = frozenset({"tick"})
"""Mission log records that are not events on MQTT (the state message carries them)."""
BATCH = 64
"""Events in flight at once (QoS 1); the broker keeps their order."""
_RECANCEL_S = 0.5
"""How long a cancelled MQTT task gets before it is cancelled again (see cancel_and_wait)."""


def _json(data: dict[str, Any]) -> bytes:
    return json.dumps(data, separators=(",", ":"), default=str).encode()


class VehicleTelemetry:
    """MQTT for one vehicle; an EventSink. Use :meth:`running` around the mission."""

    def __init__(
        self,
        settings: MqttSettings,
        topics: VehicleTopics,
        outbox: EventOutbox,
        *,
        state_rate: float,
        drain_timeout: float = 5.0,
    ) -> None:
        self.topics = topics
        self.outbox = outbox
        self.state_period = 1.0 / state_rate
        self.drain_timeout = drain_timeout
        self.vehicle: Operated | None = None
        self.channel = MqttChannel(
            settings,
            client_id=f"{topics.prefix}/{topics.name}".replace("/", "-"),
            will=aiomqtt.Will(topics.status, self._status("offline", clean=False), 1, True),
            on_connect=self._announce,
        )
        self.channel.subscribe(topics.cmd, self._on_command)
        self.channel.subscribe(topics.fleet_cmd, self._on_command)

    @classmethod
    def open(
        cls, spec: MqttSpec, *, profile_name: str, vehicle: int, log_dir: Path
    ) -> VehicleTelemetry:
        """Settings, topics and the outbox (``log_dir/mqtt-outbox-I.jsonl``) of ``vehicle``."""
        topics = VehicleTopics(spec.topic_prefix or default_prefix(profile_name), vehicle)
        outbox = EventOutbox(log_dir / f"mqtt-outbox-{vehicle}.jsonl")
        return cls(settings_for(spec, vehicle), topics, outbox, state_rate=spec.state_rate)

    def emit(self, t: float, event: str, **fields: Any) -> None:
        if event not in NOT_PUBLISHED:
            record = {"vehicle": self.topics.vehicle, "t": round(t, 3), "event": event}
            self.outbox.append(record | fields)

    @contextlib.asynccontextmanager
    async def running(self, vehicle: Operated) -> AsyncIterator[None]:
        """Connect and serve while the body runs; then deliver what is left (bounded) and leave."""
        self.vehicle = vehicle
        tasks = self._start()
        try:
            yield
        finally:
            await self._drain()
            for task in tasks:
                await cancel_and_wait(task)
            self.outbox.close()

    # -- loops -----------------------------------------------------------------------------

    def _start(self) -> list[asyncio.Task[None]]:
        """The connection, the event delivery and the state loop, each a task of its own that
        ``running`` cancels and waits for by itself: in a TaskGroup only the group's first
        cancellation reaches them, and a loop that lost it (cancel_and_wait) ran on forever.
        One of them failing stops the others; the events stay in the outbox."""
        n = self.topics.vehicle
        tasks = [
            asyncio.create_task(self.channel.run(), name=f"v{n}-mqtt-connection"),
            asyncio.create_task(self._deliver(), name=f"v{n}-mqtt-events"),
            asyncio.create_task(self._publish_state(), name=f"v{n}-mqtt-state"),
        ]

        def stopped(task: asyncio.Task[None]) -> None:
            if task.cancelled() or task.exception() is None:
                return
            log.error(
                "MQTT stopped; events stay in %s for the next start",
                self.outbox.path,
                exc_info=task.exception(),
            )
            for other in tasks:
                other.cancel()

        for task in tasks:
            task.add_done_callback(stopped)
        return tasks

    async def _deliver(self) -> None:
        """Send the outbox oldest first; acknowledge the delivered prefix of each batch."""
        while True:
            await self.outbox.ready.wait()
            await self.channel.connected.wait()
            batch = self.outbox.pending(BATCH)
            results = await asyncio.gather(
                *(self.channel.publish(self.topics.event, p, qos=1) for _, p in batch),
                return_exceptions=True,
            )
            done = sum(1 for _ in itertools.takewhile(lambda r: r is None, results))
            if done:
                self.outbox.ack(batch[done - 1][0])
            if done < len(batch):
                log.warning(
                    "event %d not delivered (%s); %d waiting",
                    batch[done][0],
                    results[done],
                    len(self.outbox),
                )
                await asyncio.sleep(0.5)  # the connection notices and reconnects

    async def _publish_state(self) -> None:
        while True:
            await asyncio.sleep(self.state_period)
            if self.vehicle is None or not self.channel.connected.is_set():
                continue  # state is not buffered: only the latest one matters
            try:
                await self.channel.publish(self.topics.state, _json(self.vehicle.snapshot()))
            except aiomqtt.MqttError as exc:
                log.debug("state not sent: %s", exc)

    async def _announce(self) -> None:
        await self.channel.publish(self.topics.status, self._status("online"), qos=1, retain=True)

    async def _drain(self) -> None:
        loop = asyncio.get_running_loop()
        deadline = loop.time() + self.drain_timeout
        while len(self.outbox) and loop.time() < deadline:
            await asyncio.sleep(0.05)
        if len(self.outbox):
            log.warning(
                "%d event(s) not delivered; kept in %s for the next start",
                len(self.outbox),
                self.outbox.path,
            )
        if not self.channel.connected.is_set():
            return
        if self.vehicle is not None:  # the last state: the end action's mode, landed
            with contextlib.suppress(aiomqtt.MqttError):
                state = _json(self.vehicle.snapshot())
                await self.channel.publish(self.topics.state, state, timeout=2.0)
        with contextlib.suppress(aiomqtt.MqttError):  # offline even when that one failed
            await self.channel.publish(
                self.topics.status,
                self._status("offline", clean=True),
                qos=1,
                retain=True,
                timeout=2.0,
            )

    # -- commands --------------------------------------------------------------------------

    def _on_command(self, msg: Received) -> None:
        vehicle = self.vehicle
        if vehicle is None:
            return
        if msg.retained:
            self._refuse(vehicle, msg, "retained command ignored (publish commands without retain)")
            return
        try:
            command = parse_command(msg.payload)
        except CommandError as exc:
            self._refuse(vehicle, msg, str(exc))
            return
        log.info("operator command %s (id %s) on %s", command.name, command.id, msg.topic)
        vehicle.emit("command", command=command.name, id=command.id, topic=msg.topic)
        refusal = obey(command, vehicle)
        if refusal is not None:
            self._refuse(vehicle, msg, refusal)

    @staticmethod
    def _refuse(vehicle: Operated, msg: Received, why: str) -> None:
        log.warning("command on %s refused: %s", msg.topic, why)
        vehicle.emit(
            "error",
            source="command",
            topic=msg.topic,
            error=why,
            payload=msg.payload[:200].decode("utf-8", "replace"),
        )

    def _status(self, state: str, *, clean: bool = True) -> bytes:
        return _json({"vehicle": self.topics.vehicle, "state": state, "clean": clean})


async def cancel_and_wait(task: asyncio.Task[None]) -> None:
    """Cancel ``task`` and wait until it has ended, cancelling again every _RECANCEL_S.

    On Python 3.11, asyncio.wait_for loses a cancellation that arrives in the loop iteration
    its wait completes in (CPython issue 86296, fixed in 3.12), and aiomqtt waits for every
    publish through it. A state loop that lost its cancellation ran on and the companion
    never exited (seen under load: `fleet did not end`, a companion killed after its mission)."""
    while not task.done():
        task.cancel()
        await asyncio.wait({task}, timeout=_RECANCEL_S)
    if not task.cancelled():
        task.exception()  # logged by _start's callback; retrieved so asyncio does not warn
