"""The world of a mission profile: area, targets, their motion and the sensors."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mdm_core.world.area import Area
from mdm_core.world.sensors import Sensor
from mdm_core.world.targets import RandomWalk, TargetSpec, TargetTracks
from mdm_profiles import MissionProfile

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Scenario:
    """Everything about the world that a profile fixes (no vehicles, no policy)."""

    area: Area
    targets: TargetSpec
    walk: RandomWalk | None
    sensors: tuple[Sensor, ...]
    """Detection sensors by decreasing radius, then the confirmation sensor."""
    grid_dt: float = 10.0

    @classmethod
    def from_profile(cls, profile: MissionProfile) -> Scenario:
        targets = TargetSpec(
            positions=np.array([[t.north, t.east] for t in profile.targets], dtype=float),
            appear_times=np.array([t.appear for t in profile.targets], dtype=float),
            false_mask=np.array([t.false_target for t in profile.targets], dtype=bool),
        )
        motion = profile.target_motion
        walk = None
        grid_dt = 10.0
        if motion is not None:
            walk = RandomWalk(
                speed=motion.speed,
                low=motion.low,
                high=motion.high,
                sample_time=motion.sample_time,
                shared_axes=motion.shared_axes,
                boundary=motion.boundary,
            )
            grid_dt = motion.grid_dt
        n = len(profile.sensors)
        sensors = tuple(
            Sensor(name=s.name, radius=s.radius, confirms=(i == n - 1))
            for i, s in enumerate(profile.sensors)
        )
        return cls(Area(profile.area.north, profile.area.east), targets, walk, sensors, grid_dt)

    @property
    def confirmation(self) -> Sensor:
        return self.sensors[-1]

    def tracks(self, n_runs: int, rng: np.random.Generator) -> TargetTracks:
        """Target tracks for ``n_runs`` independent runs drawn from ``rng``."""
        return TargetTracks(self.targets, self.area, n_runs, rng, self.walk, self.grid_dt)

    def live_run(
        self,
        seed: int,
        n_vehicles: int,
        placement: str,
        start: FloatArray | None = None,
    ) -> tuple[FloatArray, TargetTracks]:
        """Start positions (n_vehicles, 2) and the one run of targets a live mission with ``seed``
        has: the emulator and the companion's virtual sensors both call this, so the same seed
        places the same targets on both (the draws' order is part of that contract). Given
        ``start`` positions draw nothing, so the targets then differ from a drawn start's."""
        rng = np.random.default_rng(seed)
        if start is None:
            start = self.start_positions(1, n_vehicles, placement, rng)[0]
        return start, self.tracks(1, rng)

    def start_positions(
        self, n_runs: int, n_vehicles: int, placement: str, rng: np.random.Generator
    ) -> np.ndarray:
        """Start positions (n_runs, n_vehicles, 2) on the periphery of the area."""
        if placement == "periphery_even":
            offset = rng.uniform(0.0, 1.0, size=(n_runs, 1))
            s = offset + np.arange(n_vehicles)[None, :] / n_vehicles
        else:
            s = rng.uniform(0.0, 1.0, size=(n_runs, n_vehicles))
        return self.area.perimeter_point(s)
