"""Sensor readings carried over MAVLink (docs/protocol.md): DEBUG_VECT 'DET' / 'CNF' contacts.

The sensor is switched with PARAM_SET MDM_SENSOR; the switch is sent by a background task so
the decision loop never waits for the vehicle's answer.
"""

from __future__ import annotations

import asyncio
import logging

import numpy as np

from companion.link.base import VehicleLink
from companion.link.messages import SensorContact, SensorSignal
from companion.link.outcome import Outcome
from companion.sensors.base import FloatArray, SensorSource

log = logging.getLogger(__name__)


class MavlinkSensorSource(SensorSource):
    """Contacts from DEBUG_VECT messages; sensor ``n_sensors - 1`` confirms ('CNF'), others 'DET'."""

    def __init__(self, link: VehicleLink, n_sensors: int) -> None:
        super().__init__()
        self._link = link
        self._n = n_sensors
        self._active = -1
        self._since = 0.0
        self._pending: list[tuple[float, float]] = []
        self._wanted: asyncio.Queue[int] = asyncio.Queue()

    @property
    def active(self) -> int:
        return self._active

    def waiting(self) -> FloatArray:
        """What the next :meth:`take` gives (the contacts stay)."""
        return np.array(self._pending, dtype=float) if self._pending else np.zeros((0, 2))

    def expected_kind(self) -> str:
        return "CNF" if self._active == self._n - 1 else "DET"

    def select(self, index: int, time: float) -> None:
        if not -1 <= index < self._n:
            raise ValueError(f"sensor index {index} outside -1..{self._n - 1}")
        if index != self._active:
            self._active = index
            self._since = time
            self._pending.clear()
        self._wanted.put_nowait(index)

    def accept(self, event: SensorContact | SensorSignal) -> None:
        """Feed one reading from the link."""
        if isinstance(event, SensorSignal):
            self.signal = event.value
            return
        if self._active < 0 or event.kind != self.expected_kind() or event.time < self._since:
            return
        self._pending.append((event.north, event.east))

    def take(self) -> FloatArray:
        out = self.waiting()
        self._pending.clear()
        return out

    async def run(self) -> None:
        """Send the latest wanted sensor to the vehicle (retried by the link)."""
        while True:
            index = await self._wanted.get()
            while not self._wanted.empty():
                index = self._wanted.get_nowait()
            if index != self._active:
                continue  # superseded while queued
            result = await self._link.set_sensor(index)
            if result:
                continue
            if result.outcome is Outcome.DENIED:  # no such parameter, or it keeps another value
                log.warning("sensor switching off: %s", result.describe())
                return
            log.warning(
                "vehicle did not confirm sensor %d (%s); retrying", index, result.describe()
            )
            self._wanted.put_nowait(self._active)
            await asyncio.sleep(1.0)
