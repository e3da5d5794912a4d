"""Detection and confirmation sensors (eqs. 5-6): signal strength, threshold, contacts.

A sensor of radius r reads a signal strength s(d) = exp(-d / r) from a target at distance d; the
threshold is exp(-1), so s > threshold exactly when d < r, as eqs. (5) and (6) state. Detection
sensors see every present target, false ones included; the confirmation sensor sees only real
targets and reports their position.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

THRESHOLD = float(np.exp(-1.0))
REACH_SLACK = 1e-6
"""Metres added to the reach bound so rounding never drops a pair the exact test keeps."""


@dataclass(frozen=True)
class Sensor:
    """One sensor of a vehicle."""

    name: str
    """Label used in logs and messages ("detection", "confirmation")."""
    radius: float
    """Sensing radius r_k, metres."""
    confirms: bool
    """True for the confirmation sensor: it never fires on false targets."""

    def __post_init__(self) -> None:
        if not self.radius > 0:
            raise ValueError(f"sensor {self.name!r}: radius must be > 0 m, got {self.radius}")

    def strength(self, distance: FloatArray) -> FloatArray:
        """Signal strength for targets at the given distances (1 at the target, e^-1 at r)."""
        return np.exp(-np.asarray(distance, dtype=float) / self.radius)


def contacts(
    radius: FloatArray,
    confirms: BoolArray,
    vehicle: FloatArray,
    targets: FloatArray,
    present: BoolArray,
    false_mask: BoolArray,
) -> tuple[BoolArray, FloatArray]:
    """Which targets each vehicle's active sensor reports, and their signal strengths.

    radius, confirms: (n,) active sensor per vehicle; vehicle: (n, 2); targets: (n, m, 2);
    present: (n, m) targets that have appeared; false_mask: (m,).
    Returns (mask (n, m), strength (n, m)); strength is exp(-d / r) for every target.
    """
    distance = np.linalg.norm(targets - vehicle[:, None, :], axis=-1)
    strength = np.exp(-distance / radius[:, None])
    seen = present & ~(confirms[:, None] & false_mask[None, :])
    mask = seen & (strength > THRESHOLD) & (distance < radius[:, None])
    return mask, strength


def first_entry_time(
    start: FloatArray,
    velocity: FloatArray,
    duration: FloatArray,
    target_start: FloatArray,
    target_velocity: FloatArray,
    radius: FloatArray,
    eligible: BoolArray,
    not_before: FloatArray,
    target_speed: float | None = None,
) -> FloatArray:
    """Earliest s in [not_before, duration] at which a vehicle moving linearly is within radius.

    Both vehicle (n, 2) and targets (n, m, 2) move linearly for ``duration`` (n,) seconds.
    Returns (n, m) times from the start of the interval, inf where the disc is not reached or the
    target is not eligible. The time returned is the boundary crossing itself (distance = r).

    Only pairs that can meet are solved: a vehicle closes on a target at most at the sum of
    their speeds, so a target farther than r + (|v| + |v_target|) * duration is out of reach.
    ``target_speed``: a bound on every target's speed, if the caller knows one (else computed).
    """
    north = start[:, 0, None] - target_start[..., 0]
    east = start[:, 1, None] - target_start[..., 1]
    dist2 = north * north + east * east
    lo = np.maximum(np.broadcast_to(not_before, dist2.shape), 0.0)
    # Closing speed bound: the vehicle's speed plus the fastest target's.
    vehicle_speed = np.sqrt(velocity[:, 0] ** 2 + velocity[:, 1] ** 2)
    if target_speed is None:
        target_speed = float(np.sqrt(np.max(target_velocity**2, initial=0.0) * 2.0))
    reach = radius + (vehicle_speed + target_speed) * duration + REACH_SLACK
    reach = reach[:, None]
    candidate = eligible & (dist2 <= reach * reach) & (lo <= duration[:, None])
    out = np.full(dist2.shape, np.inf)
    pairs = np.flatnonzero(candidate)
    if pairs.size:
        rows = pairs // dist2.shape[1]
        rel_v = velocity[rows] - target_velocity[rows, pairs - rows * dist2.shape[1]]
        out.ravel()[pairs] = _solve_entry(
            np.stack([north.ravel()[pairs], east.ravel()[pairs]], axis=-1),
            rel_v,
            dist2.ravel()[pairs] - radius[rows] ** 2,
            lo.ravel()[pairs],
            duration[rows],
        )
    return out


def _solve_entry(
    rel0: FloatArray, rel_v: FloatArray, c: FloatArray, lo: FloatArray, duration: FloatArray
) -> FloatArray:
    """First time in [lo, duration] at which |rel0 + rel_v s| <= r, given c = |rel0|^2 - r^2."""
    a = np.einsum("ik,ik->i", rel_v, rel_v)
    b = np.einsum("ik,ik->i", rel0, rel_v)
    disc = b * b - a * c
    moving = a > 1e-12
    root = np.sqrt(np.maximum(disc, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        s1 = np.where(moving, (-b - root) / np.where(moving, a, 1.0), -np.inf)
        s2 = np.where(moving, (-b + root) / np.where(moving, a, 1.0), np.inf)
    hit = np.where(moving, disc > 0, c < 0)
    first = np.maximum(s1, lo)
    ok = hit & (first < s2) & (first <= duration)
    return np.where(ok, first, np.inf)
