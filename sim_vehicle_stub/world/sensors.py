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
) -> FloatArray:
    """Earliest s in [not_before, duration] at which a vehicle moving linearly is within radius.

    Both vehicle (n, 2) and targets (n, m, 2) move linearly for ``duration`` (n,) seconds.
    Returns (n, m) times from the start of the interval, inf where the disc is not reached or the
    target is not eligible. The time returned is the boundary crossing itself (distance = r).
    """
    rel0 = start[:, None, :] - target_start
    rel_v = velocity[:, None, :] - target_velocity
    a = np.einsum("nmk,nmk->nm", rel_v, rel_v)
    b = np.einsum("nmk,nmk->nm", rel0, rel_v)
    c = np.einsum("nmk,nmk->nm", rel0, rel0) - radius[:, None] ** 2
    disc = b * b - a * c
    moving = a > 1e-12
    root = np.sqrt(np.maximum(disc, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        s1 = np.where(moving, (-b - root) / np.where(moving, a, 1.0), -np.inf)
        s2 = np.where(moving, (-b + root) / np.where(moving, a, 1.0), np.inf)
    hit = np.where(moving, disc > 0, c < 0)
    lo = np.maximum(not_before, 0.0)
    first = np.maximum(s1, lo)
    ok = eligible & hit & (first < s2) & (first <= duration[:, None])
    return np.where(ok, first, np.inf)
