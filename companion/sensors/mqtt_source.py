"""Detections from an onboard detector over MQTT (``<prefix>/uav<i>/detections``, docs/mqtt.md).

The detector publishes one JSON object per frame: what the named sensor saw, or that it saw
nothing (which keeps it counted as alive). A bad payload is an ``error`` event and is ignored;
a detector silent for ``silence_timeout`` wall seconds is reported (a ``detector`` event,
``state: silent``) and again when it is heard (``state: alive``). Wall seconds, not vehicle
seconds: the detector is a real process beside the companion, like the link time-out.
"""

from __future__ import annotations

import asyncio
import logging
from time import time as wall_time

import numpy as np

from companion.link.local_frame import LocalFrame
from companion.sensors.base import FloatArray, SensorSource
from companion.sensors.detection_payload import DetectionError, parse_detection
from companion.telemetry.mqtt.channel import MqttChannel, Received
from mdm_profiles import MissionProfile

log = logging.getLogger(__name__)
_CHECK_PERIOD = 0.5
"""Wall seconds between checks for a silent detector."""


class MqttSensorSource(SensorSource):
    """Contacts of the active sensor from the detector's messages since the last switch."""

    def __init__(self, channel: MqttChannel, topic: str, profile: MissionProfile) -> None:
        super().__init__()
        self.topic = topic
        self._names = tuple(s.name for s in profile.sensors)
        o = profile.origin
        self._frame = LocalFrame(o.lat, o.lon, o.alt)
        spec = profile.sensor_source
        self._silence = spec.silence_timeout
        self._min_confidence = spec.min_confidence
        self._active = -1
        self._since_wall = 0.0
        self._pending: list[tuple[float, float]] = []
        self._heard = wall_time()
        self._silent = False
        self.received = 0
        """Valid messages received (frames with and without a detection)."""
        self.rejected = 0
        channel.subscribe(topic, self._on_message)

    @property
    def active(self) -> int:
        return self._active

    def select(self, index: int, time: float) -> None:
        if not -1 <= index < len(self._names):
            raise ValueError(f"sensor index {index} outside -1..{len(self._names) - 1}")
        if index != self._active:
            self._active = index
            # The detector stamps frames by its own (wall) clock; vehicle time cannot say
            # which of its frames were taken before the switch.
            self._since_wall = wall_time()
            self._pending.clear()

    def take(self) -> FloatArray:
        if not self._pending:
            return np.zeros((0, 2))
        out = np.array(self._pending, dtype=float)
        self._pending.clear()
        return out

    async def run(self) -> None:
        self._heard = wall_time()
        while True:
            await asyncio.sleep(_CHECK_PERIOD)
            silent = wall_time() - self._heard
            if not self._silent and silent >= self._silence:
                self._silent = True
                log.warning("detector silent for %.1f s on %s", silent, self.topic)
                self.report("detector", state="silent", silent_s=round(silent, 1), topic=self.topic)

    def _on_message(self, msg: Received) -> None:
        if msg.retained:
            self._refuse(msg, "retained detection ignored (publish detections without retain)")
            return
        try:
            detection = parse_detection(msg.payload, self._names, self._frame)
        except DetectionError as exc:
            self._refuse(msg, str(exc))
            return
        self.received += 1
        self._heard = wall_time()
        if self._silent:
            self._silent = False
            log.info("detector heard again on %s", self.topic)
            self.report("detector", state="alive", topic=self.topic)
        if (
            detection.position is None
            or detection.sensor != self._active
            or detection.time < self._since_wall
            or (detection.confidence is not None and detection.confidence < self._min_confidence)
        ):
            return
        self._pending.append(detection.position)

    def _refuse(self, msg: Received, why: str) -> None:
        self.rejected += 1
        log.warning("detection on %s refused: %s", msg.topic, why)
        self.report(
            "error",
            source="detector",
            topic=msg.topic,
            error=why,
            payload=msg.payload[:200].decode("utf-8", "replace"),
        )
