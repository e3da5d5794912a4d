"""The sensor-source interface: where a companion's target contacts come from.

Sources: :class:`~companion.sensors.mavlink_source.MavlinkSensorSource` (readings that the
vehicle or the emulator sends over MAVLink); an MQTT topic or a local driver fit the same
interface (not written yet).
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


class SensorSource(ABC):
    """Switches the payload sensors and hands the contacts of the active one to the policy."""

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
