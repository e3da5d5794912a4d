"""The sensor-source interface: where a companion's target contacts come from.

Sources (``sensor_source.kind`` of the profile, ``--sensor-source`` on the command line):
:class:`~companion.sensors.mavlink_source.MavlinkSensorSource` (readings the vehicle or the
emulator sends over MAVLink), :class:`~companion.sensors.virtual_source.VirtualSensorSource`
(the profile's targets read against the vehicle's position with the paper's sensor model) and
:class:`~companion.sensors.mqtt_source.MqttSensorSource` (an onboard detector on MQTT).
"""

from __future__ import annotations

import asyncio
from abc import ABC, abstractmethod
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from companion.link.messages import SensorContact, SensorSignal

FloatArray = NDArray[np.float64]


class Reporter(Protocol):
    """Where a source reports what the operator must know (the mission's ``emit``)."""

    def __call__(self, event: str, **fields: object) -> None: ...


def _unreported(event: str, **fields: object) -> None:
    """Before the mission binds its log: nothing to report to yet."""


class SensorSource(ABC):
    """Switches the payload sensors and hands the contacts of the active one to the policy."""

    def __init__(self) -> None:
        self.signal = 0.0
        """Latest strongest-signal reading of the active sensor (exp(-d/r)); 0 when unknown."""
        self.report: Reporter = _unreported
        """Mission-log events of the source (errors, a silent detector); set by the mission."""

    @property
    @abstractmethod
    def active(self) -> int:
        """Index of the sensor switched on (0 = first detection sensor, last = confirmation)."""

    @abstractmethod
    def select(self, index: int, time: float) -> None:
        """Switch to sensor ``index`` at vehicle time ``time``; readings older than that are stale."""

    @abstractmethod
    def take(self) -> FloatArray:
        """(m, 2) positions (north, east) of the active sensor's contacts since the last call."""

    # Not abstract: a default that drops what the source does not use.
    def accept(self, event: SensorContact | SensorSignal) -> None:  # noqa: B027
        """A reading that came over the vehicle link; sources that do not read MAVLink drop it."""

    def observe(self, time: float, north: float, east: float) -> None:  # noqa: B027
        """The vehicle's position (profile frame) at vehicle time ``time``."""

    async def run(self) -> None:
        """The source's background work for the whole mission (cancelled at its end)."""
        await asyncio.Event().wait()
