"""The page's MQTT side: the team's state, event and status topics in, operator commands out."""

from __future__ import annotations

import json
import logging
import re
import time
from typing import Any

import aiomqtt

from companion.telemetry.mqtt.channel import MqttChannel, Received
from companion.telemetry.mqtt.settings import MqttSettings
from mdm_ground.live_web.fleet_state import CommandOutcome, FleetState

log = logging.getLogger(__name__)
_TOPIC = re.compile(r"uav(\d{1,4})/(state|event|status)")


class MqttFeed:
    """Feeds ``state`` from ``<prefix>/uav<i>/state|event|status``; publishes commands on
    ``<prefix>/uav<i>/cmd`` and ``<prefix>/all/cmd``."""

    def __init__(self, settings: MqttSettings, prefix: str, state: FleetState) -> None:
        self.prefix = prefix
        self.state = state
        self.channel = MqttChannel(settings, client_id=f"live-web-{time.time_ns() % 10**9}")
        for leaf in ("state", "event", "status"):
            self.channel.subscribe(f"{prefix}/+/{leaf}", self._on_message)
        self.refused = 0
        """Messages on the team's topics that were not understood (logged)."""
        self._last_seq: dict[int, int] = {}

    def _on_message(self, msg: Received) -> None:
        m = _TOPIC.fullmatch(msg.topic[len(self.prefix) + 1 :])
        if m is None:
            return
        vehicle, leaf = int(m.group(1)), m.group(2)
        try:
            payload: Any = json.loads(msg.payload)
        except (UnicodeDecodeError, json.JSONDecodeError):
            payload = None
        if not isinstance(payload, dict):
            self.refused += 1
            log.warning("%s: not a JSON object, ignored: %r", msg.topic, msg.payload[:80])
            return
        wall = time.time()
        if leaf == "state":
            self.state.on_state(vehicle, payload, wall)
        elif leaf == "status":
            self.state.on_status(vehicle, payload, wall)
        elif self._fresh(vehicle, payload.get("seq")):
            self.state.on_event(vehicle, payload, wall)

    def _fresh(self, vehicle: int, seq: Any) -> bool:
        """Not an event seen already: QoS 1 may deliver one twice after a reconnect, and a
        vehicle's ``seq`` only grows (docs/mqtt.md)."""
        if isinstance(seq, bool) or not isinstance(seq, int):
            return True
        if seq <= self._last_seq.get(vehicle, -1):
            return False
        self._last_seq[vehicle] = seq
        return True

    async def send(self, vehicle: int | None, command: str, ref: str) -> None:
        """Publish one command (QoS 1, not retained); raises aiomqtt.MqttError when the broker
        does not take it."""
        target = "all" if vehicle is None else f"uav{vehicle}"
        body = json.dumps({"command": command, "id": ref}).encode()
        outcome = CommandOutcome(ref, command, target, time.time())
        self.state.sent(outcome)  # before publishing: the answer may come back at once
        try:
            await self.channel.publish(f"{self.prefix}/{target}/cmd", body, qos=1)
        except aiomqtt.MqttError as exc:
            self.state.not_sent(outcome, str(exc))
            raise
