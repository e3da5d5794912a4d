"""Virtual sensors: the profile's targets read against the vehicle's real position.

For SITL and field rehearsal, where no payload sensor reports anything: the companion places
the profile's targets (fixed, pop-up, dynamic, false) exactly as the emulator would with the
same seed (``Scenario.live_run``) and reads them with the paper's sensor model (eqs. 5-6,
``mdm_core.world.contacts``) at every position the vehicle reports. Times are mission time
(vehicle seconds), as on the emulator's clock, so a pop-up target appears at the same time.
"""

from __future__ import annotations

import numpy as np

from companion.sensors.base import FloatArray, SensorSource
from mdm_core.world import Scenario, contacts
from mdm_profiles import MissionProfile

_RUN = np.zeros(1, dtype=np.intp)


class VirtualSensorSource(SensorSource):
    """Contacts of the active sensor with the profile's targets at each observed position."""

    def __init__(self, profile: MissionProfile, seed: int) -> None:
        super().__init__()
        self.scenario = Scenario.from_profile(profile)
        _, self.tracks = self.scenario.live_run(seed, profile.fleet.vehicles, profile.fleet.start)
        self._active = -1
        self._since = 0.0
        self._pending: dict[int, tuple[float, float]] = {}
        """Target index -> its latest contact position since the last ``take``."""

    @property
    def active(self) -> int:
        return self._active

    def select(self, index: int, time: float) -> None:
        n = len(self.scenario.sensors)
        if not -1 <= index < n:
            raise ValueError(f"sensor index {index} outside -1..{n - 1}")
        if index != self._active:
            self._active = index
            self._since = time
            self._pending.clear()
            self.signal = 0.0

    def targets_at(self, time: float) -> FloatArray:
        """(m, 2) target positions at mission time ``time`` (appeared or not)."""
        return np.asarray(self.tracks.positions(_RUN, np.array([time]))[0], dtype=np.float64)

    def observe(self, time: float, north: float, east: float) -> None:
        if self._active < 0 or time < self._since:
            return
        spec = self.scenario.targets
        sensor = self.scenario.sensors[self._active]
        targets = self.targets_at(time)
        present = spec.appear_times <= time
        mask, strength = contacts(
            np.array([sensor.radius]),
            np.array([sensor.confirms]),
            np.array([[north, east]]),
            targets[None],
            present[None],
            spec.false_mask,
        )
        visible = present & ~(sensor.confirms & spec.false_mask)
        # The strongest reading over every target this sensor can see, as the emulator's SENS_SIG.
        self.signal = float(np.where(visible, strength[0], 0.0).max(initial=0.0))
        for k in np.flatnonzero(mask[0]).tolist():
            self._pending[k] = (float(targets[k, 0]), float(targets[k, 1]))

    def take(self) -> FloatArray:
        if not self._pending:
            return np.zeros((0, 2))
        out = np.array(list(self._pending.values()), dtype=float)
        self._pending.clear()
        return out
