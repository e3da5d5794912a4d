"""Configuration of the search levels: sensor, distribution, step length, decaying index."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from mdm_core.search.distributions import Sampler

StepLaw = Literal["fixed", "levy"]
OutOfArea = Literal["reflect", "clip", "redraw"]
WaypointOrigin = Literal["position", "anchor"]
AnchorAt = Literal["vehicle", "target"]
Redetection = Literal["ignore", "recentre", "renew"]
DetectionMemory = Literal["disc", "exact", "none"]
IndexStart = Literal["printed", "max"]


@dataclass(frozen=True)
class DecayIndex:
    """The confirmation index C_I (or detection index D^k_I) of section III.

    C_I(t_s) = gamma + (index_max - index_min) exp(-t_s / kappa); the level ends when
    C_I < index_min, that is once t_s exceeds ``lifetime``.
    """

    gamma: float = 0.1
    """Gamma, 0 < Gamma < index_min."""
    index_max: float = 0.95
    """C_Imax, the value set on entering the level (close to one)."""
    index_min: float = 0.2
    """C_Imin, the lower bound that ends the level."""
    kappa: float = 150.0
    """kappa > 0, seconds."""
    start: IndexStart = "printed"
    """printed: C_I = gamma + (index_max - index_min) e^(-t/kappa), the formula as printed,
    which starts at gamma + index_max - index_min (0.85 with the defaults), not at index_max.
    max: C_I = gamma + (index_max - gamma) e^(-t/kappa), which starts at index_max as the text
    says ("set to a value closer to one denoted by C_Imax")."""

    def __post_init__(self) -> None:
        if not 0 < self.gamma < self.index_min < self.index_max:
            raise ValueError(
                "decay index needs 0 < gamma < index_min < index_max, got "
                f"gamma={self.gamma}, index_min={self.index_min}, index_max={self.index_max}"
            )
        if not self.kappa > 0:
            raise ValueError(f"decay index kappa must be > 0 s, got {self.kappa}")
        if self.gamma + self.index_max - self.index_min <= self.index_min:
            raise ValueError(
                "decay index starts below index_min (gamma + index_max - index_min <= index_min):"
                " the level would end the moment it starts"
            )

    @property
    def _range(self) -> float:
        """Coefficient of the exponential: C_I(0) - gamma."""
        top = self.index_min if self.start == "printed" else self.gamma
        return self.index_max - top

    def value(self, time_in_level: np.ndarray) -> np.ndarray:
        """C_I after ``time_in_level`` seconds on the level."""
        return self.gamma + self._range * np.exp(-time_in_level / self.kappa)

    @property
    def lifetime(self) -> float:
        """Seconds on the level after which C_I < index_min (closed form of eq. 13)."""
        ratio = self._range / (self.index_min - self.gamma)
        return float(self.kappa * np.log(ratio))


@dataclass(frozen=True)
class Level:
    """One search level: which sensor is on, how waypoints are drawn, when the level ends."""

    sampler: Sampler
    """Direction distribution D(S_t) of this level."""
    step: float
    """Step length delta_k, metres."""
    sensor_radius: float
    """Radius of the sensor used on this level, metres (r_k)."""
    index: DecayIndex | None = None
    """Decaying index that ends the level (None on level 1, which never times out)."""
    step_law: StepLaw = "fixed"
    """fixed: every step is delta_k (eq. 7). levy: delta_k times |Levy(step_index)|."""
    step_index: float = 1.0
    """Stability index of the Levy step-length law."""
    step_cap: float = 5.0
    """Longest Levy step, in multiples of delta_k."""

    def __post_init__(self) -> None:
        if not self.step > 0:
            raise ValueError(f"step length must be > 0 m, got {self.step}")
        if not self.sensor_radius > 0:
            raise ValueError(f"sensor radius must be > 0 m, got {self.sensor_radius}")


@dataclass(frozen=True)
class PolicyConfig:
    """A whole search policy. One level is a single-sensor search (US, BS, LS); n >= 2 is MDM."""

    levels: tuple[Level, ...]
    """Levels 1..n; the last uses the confirmation sensor, the others detection sensors."""
    area: tuple[float, float]
    """Search area extent (north, east), metres, from the origin."""
    out_of_area: OutOfArea = "reflect"
    """What to do with a waypoint outside the area: mirror it, clip it, or draw again."""
    fence: tuple[tuple[float, float, float], ...] = ()
    """Half-planes (n_north, n_east, offset) of a field's inset fence: with 'redraw', a waypoint
    counts as inside only where n_north * north + n_east * east >= offset for each one too
    (mdm_core.world.fence_planes). Empty: the area alone (paper profiles)."""
    waypoint_origin: WaypointOrigin = "position"
    """Levels >= 2: step from the current position (eq. 7) or from the point of detection."""
    confine_to_detection: bool = True
    """Levels >= 2: keep waypoints within the previous sensor's radius of the point of detection."""
    anchor_at: AnchorAt = "vehicle"
    """A detection's anchor: the vehicle's position, or the detected target's (the first in
    target order where several are detected at once)."""
    redetection: Redetection = "ignore"
    """The detection sensor read on the last level as well, at the steps where the vehicle
    reaches its waypoint or its index runs out (Observation.detections): ignore; recentre (a
    detection moves the anchor as anchor_at says); renew (recentre, and the level's clock
    starts again). Detections there are checked against memory as detection_memory says."""
    memory_radius: float = 400.0
    """A contact within this distance of a target I confirmed is that target again (metres)."""
    detection_memory: DetectionMemory = "disc"
    """How a detection-level contact is checked against the targets this vehicle confirmed.
    The detection sensor gives no position (section II: "only the spatial distribution"):
    disc: the detection is ignored while a remembered target lies within the sensor's radius
    of the vehicle (it may be that target); none: never ignored; exact: ignored when the
    contacted target's true position is within memory_radius of a remembered one (uses what
    the sensor cannot give). Confirmation contacts carry a position: always checked exactly."""
    fallback_blind_time: float = 0.0
    """Seconds after the decaying index ends a level during which level 1 ignores detections
    (0: none; the vehicle usually still lies within r_1 of the same target and re-detects it at
    once)."""
    name: str = field(default="")
    """Label for tables: 'MDM (LS+BS)', 'US', ..."""

    def __post_init__(self) -> None:
        if not self.levels:
            raise ValueError("a policy needs at least one level")
        if self.levels[0].index is not None:
            raise ValueError("level 1 has no decaying index: it is where every fall-back goes")
        for k, level in enumerate(self.levels[1:], start=2):
            if level.index is None:
                raise ValueError(f"level {k} needs a decaying index (C_I or D_I)")
        if not self.memory_radius >= 0:
            raise ValueError(f"memory_radius must be >= 0 m, got {self.memory_radius}")
        if not self.fallback_blind_time >= 0:
            raise ValueError(f"fallback_blind_time must be >= 0 s, got {self.fallback_blind_time}")

    @property
    def label(self) -> str:
        if self.name:
            return self.name
        names = [level.sampler.name for level in self.levels]
        return names[0] if len(names) == 1 else f"MDM ({'+'.join(names)})"
