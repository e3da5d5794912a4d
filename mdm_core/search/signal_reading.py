"""The live swarm particle's fitness from the emulator's SENS_SIG, and which known target a best
came from.

SENS_SIG (docs/protocol.md, "Sensors") is the strongest exp(-d / r) of the active sensor over
every present target it can see, with no range limit and confirmed targets included; r is that
sensor's radius. The engine's fitness (mdm_core.search.pso.signal_fitness) is exp(-d / R) of the
nearest target within the swarm's signal radius R that the particle does not know to be
confirmed. Inverting SENS_SIG gives d, the distance to the nearest target; live, a target has no
index, only the position where it was confirmed, so a reading or a best is attributed to a known
target when that target lies at the distance its strength says (within ``tolerance``).
Difference from the engine: an unconfirmed target farther than a confirmed one is hidden by it.
"""

from __future__ import annotations

import numpy as np

from mdm_core.search.pso import Best, FloatArray


def distance_from_strength(strength: FloatArray, radius: float) -> FloatArray:
    """d from exp(-d / radius); inf where the strength is 0 (nothing read)."""
    with np.errstate(divide="ignore"):
        return np.asarray(np.where(strength > 0, -radius * np.log(strength), np.inf))


def fitness_from_signal(
    signal: float,
    sensor_radius: float,
    signal_radius: float,
    here: FloatArray,
    known: FloatArray,
    tolerance: float,
) -> float:
    """The engine's fitness at ``here`` (2,) from one SENS_SIG reading of a sensor of radius
    ``sensor_radius``; ``known`` (k, 2): positions of targets known to be confirmed."""
    if not signal > 0:
        return 0.0
    d = float(distance_from_strength(np.array(signal), sensor_radius))
    if d >= signal_radius:
        return 0.0
    if len(known) and bool((np.abs(np.linalg.norm(known - here, axis=-1) - d) <= tolerance).any()):
        return 0.0
    return float(np.exp(-d / signal_radius))


def attribute(best: Best, signal_radius: float, known: FloatArray, tolerance: float) -> Best:
    """``best`` with ``source`` set to the index in ``known`` (k, 2) of the target at the
    distance its fitness says (-1: none), for mdm_core.search.pso.forget."""
    if len(known) == 0:
        return Best(best.position, best.fitness, np.full_like(best.source, -1))
    d = distance_from_strength(best.fitness, signal_radius)
    gap = np.abs(np.linalg.norm(best.position[..., None, :] - known, axis=-1) - d[..., None])
    nearest = np.argmin(gap, axis=-1)
    hit = np.take_along_axis(gap, nearest[..., None], axis=-1)[..., 0] <= tolerance
    return Best(best.position, best.fitness, np.where(hit, nearest, -1).astype(np.intp))
