"""A generic MQTT publish/subscribe channel that stays connected: the one place that owns a socket.

The companion's telemetry (state, events, status, commands) is built on it, and so can any
other use (a PSO peer channel: publish my best, receive the others'). ``run`` keeps one
connection up, reconnecting with jittered exponential backoff (at most ``backoff_max`` s)
and subscribing again each time; handlers are plain functions called on the event loop, and
an exception in one is logged, never raised into the connection or its caller.
"""

from __future__ import annotations

import asyncio
import logging
import random
from collections.abc import Awaitable, Callable
from dataclasses import dataclass

import aiomqtt

from companion.errors import CompanionError
from companion.telemetry.mqtt.settings import MqttSettings

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Received:
    """One message from the broker."""

    topic: str
    payload: bytes
    retained: bool
    """Delivered from the broker's retained store (sent before we subscribed)."""


Handler = Callable[[Received], None]


class NotConnectedError(CompanionError, aiomqtt.MqttError):
    """``publish`` while no connection is up (an aiomqtt.MqttError too, as the client's own)."""


class MqttChannel:
    """One broker connection, kept up by :meth:`run` until it is cancelled."""

    def __init__(
        self,
        settings: MqttSettings,
        *,
        client_id: str,
        will: aiomqtt.Will | None = None,
        clean_session: bool = True,
        on_connect: Callable[[], Awaitable[None]] | None = None,
        backoff_max: float = 5.0,
    ) -> None:
        self.settings = settings
        self.client_id = client_id
        self.connected = asyncio.Event()
        self._will = will
        self._clean = clean_session
        self._on_connect = on_connect
        self._backoff_max = backoff_max
        self._handlers: list[tuple[str, int, Handler]] = []
        self._client: aiomqtt.Client | None = None
        self.connections = 0
        """Successful connections so far (1 + reconnections)."""

    def subscribe(self, topic_filter: str, handler: Handler, qos: int = 1) -> None:
        """Call ``handler`` for every message matching ``topic_filter`` (from the next connect on)."""
        self._handlers.append((topic_filter, qos, handler))

    async def publish(
        self,
        topic: str,
        payload: bytes,
        *,
        qos: int = 0,
        retain: bool = False,
        timeout: float = 5.0,
    ) -> None:
        """Publish now; QoS 1 returns once the broker acknowledged it. Raises ``MqttError``."""
        client = self._client
        if client is None:
            raise NotConnectedError(f"not connected to {self._where}")
        await client.publish(topic, payload, qos=qos, retain=retain, timeout=timeout)

    async def run(self) -> None:
        """Connect, subscribe, dispatch; on any connection error wait and connect again."""
        backoff = 0.5
        while True:
            client = self.settings.client(
                identifier=self.client_id, will=self._will, clean_session=self._clean
            )
            try:
                async with client:
                    for topic_filter, qos, _ in self._handlers:
                        await client.subscribe(topic_filter, qos=qos)
                    self._client = client
                    self.connected.set()
                    self.connections += 1
                    log.info("MQTT %s connected to %s", self.client_id, self._where)
                    backoff = 0.5
                    if self._on_connect is not None:
                        await self._on_connect()
                    async for message in client.messages:
                        self._dispatch(message)
            except aiomqtt.MqttError as exc:
                log.warning("MQTT %s: %s (%s); retrying", self.client_id, exc, self._where)
            finally:
                self._client = None
                self.connected.clear()
            await asyncio.sleep(backoff * (0.5 + 0.5 * random.random()))  # jittered
            backoff = min(2.0 * backoff, self._backoff_max)

    @property
    def _where(self) -> str:
        return f"{self.settings.host}:{self.settings.port}"

    def _dispatch(self, message: aiomqtt.Message) -> None:
        raw = message.payload
        payload = bytes(raw) if isinstance(raw, bytes | bytearray) else str(raw or "").encode()
        received = Received(str(message.topic), payload, bool(message.retain))
        for topic_filter, _, handler in self._handlers:
            if message.topic.matches(topic_filter):
                try:
                    handler(received)
                except Exception:
                    log.exception("MQTT handler for %s failed on %s", topic_filter, received.topic)
