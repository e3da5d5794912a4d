"""Section III-B: the probabilities P_CS(t) and P_CM(t) of eqs. (18)-(22) against simulation.

Eq. (18), a single-sensor continuous random search (a UAV sweeping a strip 2 r_n wide at speed
V over the area A):                       P_CS(t) = 1 - exp(-2 r_n V t / A).
Eq. (19), MDM once the (n-1)-th sensor detected the target at t_d < t (the search goes on
inside the detection disc A_{n-1} = pi r_{n-1}^2):
                                          P_CM(t) = 1 - (1 - P_CS(t_d)) exp(-2 r_n V (t - t_d) / A_{n-1})
and P_CM(t) = P_CS(t) before t_d (eq. 20); eqs. (21)-(22): P_CM(t) >= P_CS(t) for all t.

Eq. (19) is conditional on t_d, which the paper leaves open. To set it beside a simulation we
draw t_d as the first entry into the detection disc of the same random search, the law of
eq. (18) with r_{n-1} in place of r_n: P_D(t) = 1 - exp(-2 r_{n-1} V t / A), and average:
    P_CM(t) = (1 - P_D(t)) P_CS(t) + int_0^t P_CM(t | t_d = s) dP_D(s).
The simulated curves are the share of (run, target) pairs in which the one UAV of a run has
confirmed that target by t (one vehicle, the ten fixed targets of paper-fixed).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class SearchGeometry:
    """What eqs. (18)-(19) depend on."""

    area: float
    """A, m^2."""
    speed: float
    """||V_U||, m/s."""
    confirm_radius: float
    """r_n, m."""
    detect_radius: float
    """r_{n-1}, m."""


def p_cs(t: FloatArray, g: SearchGeometry) -> FloatArray:
    """Eq. (18)."""
    return np.asarray(1.0 - np.exp(-2.0 * g.confirm_radius * g.speed * t / g.area))


def p_cm_given(t: FloatArray, t_d: FloatArray, g: SearchGeometry) -> FloatArray:
    """Eqs. (19)-(20): P_CM(t) for a detection at t_d (arrays broadcast)."""
    disc = np.pi * g.detect_radius**2
    after = 1.0 - (1.0 - p_cs(t_d, g)) * np.exp(
        -2.0 * g.confirm_radius * g.speed * (t - t_d) / disc
    )
    return np.asarray(np.where(t < t_d, p_cs(t, g), after))


def p_cm(t: FloatArray, g: SearchGeometry, nodes: int = 2000) -> FloatArray:
    """Eq. (19) averaged over t_d ~ P_D (first entry into the detection disc), see the module
    docstring. Midpoint rule in the detection probability (2000 nodes per time)."""
    t = np.asarray(t, dtype=float)[:, None]
    rate_d = 2.0 * g.detect_radius * g.speed / g.area
    reached = 1.0 - np.exp(-rate_d * t)
    t_d = -np.log1p(-(np.arange(nodes) + 0.5) / nodes * reached) / rate_d
    conditional = p_cm_given(t, t_d, g).mean(axis=1)
    return np.asarray((1.0 - reached[:, 0]) * p_cs(t[:, 0], g) + reached[:, 0] * conditional)


def confirmed_share(per_vehicle: FloatArray, t: FloatArray) -> FloatArray:
    """Share of (run, vehicle, target) triples confirmed by each time in ``t``."""
    flat = np.sort(per_vehicle.reshape(-1))
    return np.asarray(np.searchsorted(flat, t, side="right") / flat.size)
