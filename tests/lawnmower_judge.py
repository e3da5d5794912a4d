"""What the lawnmower flight tests judge a flown track by: the vehicle's planned lanes (the
engine's plan cut to the guidance fence, computed here from the profile and seed, not read
from the companion), how far each flown point is from its sweep and which lanes were flown."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from companion.fence_from_profile import guidance_fence
from companion.mission.lawnmower_core import LawnmowerCore
from mdm_profiles import MissionProfile

Point = tuple[float, float]


def planned_lanes(profile: MissionProfile, seed: int, vehicle: int) -> np.ndarray:
    """(2 lanes, 2) the vehicle's sweep as planned (north, east), lane k from 2k to 2k + 1."""
    return LawnmowerCore(profile, seed, vehicle, guidance_fence(profile)).lanes


def _to_segment(p: Point, a: np.ndarray, b: np.ndarray) -> float:
    d = b - a
    length2 = float(d @ d)
    t = 0.0 if length2 == 0 else min(1.0, max(0.0, float((np.array(p) - a) @ d) / length2))
    q = a + t * d
    return math.hypot(p[0] - q[0], p[1] - q[1])


def off_sweep(p: Point, lanes: np.ndarray) -> float:
    """Metres from ``p`` to the sweep: its lanes and the turns between them."""
    return min(_to_segment(p, lanes[k], lanes[k + 1]) for k in range(len(lanes) - 1))


@dataclass(frozen=True)
class Sweep:
    """A track against its plan."""

    lanes: int
    """Lanes planned."""
    flown: int
    """Lanes of which at least ``share`` of the length had a flown point within ``tolerance``."""
    on_sweep: float
    """Share of the track's points within ``tolerance`` of the sweep."""
    worst: float
    """Largest distance of a track point from the sweep, m."""

    def line(self, vehicle: int) -> str:
        return (
            f"vehicle {vehicle}: {self.flown} of {self.lanes} lanes flown, "
            f"{100 * self.on_sweep:.1f} % of points on the sweep, farthest {self.worst:.0f} m"
        )


def judge_sweep(
    track: list[Point], lanes: np.ndarray, tolerance: float, share: float = 0.9
) -> Sweep:
    """``track`` (the search's points, north/east) against ``lanes``."""
    off = [off_sweep(p, lanes) for p in track]
    flown = 0
    pts = np.array(track).reshape(-1, 2)
    for k in range(0, len(lanes), 2):
        a, b = lanes[k], lanes[k + 1]
        marks = np.linspace(0.0, 1.0, 50)
        near = [
            bool(len(pts)) and float(np.min(np.hypot(*(pts - (a + m * (b - a))).T))) <= tolerance
            for m in marks
        ]
        flown += sum(near) >= share * len(marks)
    on = sum(d <= tolerance for d in off) / max(len(off), 1)
    return Sweep(len(lanes) // 2, flown, on, max(off, default=math.nan))
