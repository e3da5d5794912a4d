"""The arithmetic of ``Fleet.attitude`` compiled: the tangents of the roll and pitch that give
each vehicle's lag-loop acceleration, between numpy's cos/sin of the yaw and its arctan.

The same operations in the same order as the numpy expressions it replaces (+, -, *, / only),
so the same bits; the transcendental functions stay numpy's (its SIMD loops may round
differently from the C library that compiled code calls).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled

FloatArray = NDArray[np.float64]


def _tilt_tangents(
    ref: FloatArray, speed: FloatArray, c: FloatArray, s: FloatArray, tau: float, g: float
) -> tuple[FloatArray, FloatArray]:
    """tan(roll) and -tan(pitch) of each vehicle: its acceleration (reference minus velocity,
    over tau) turned into the body frame of yaw cosine ``c`` and sine ``s``, over g."""
    n = c.size
    right, forward = np.empty(n), np.empty(n)
    for i in range(n):
        a0 = (ref[i, 0] - speed[i, 0]) / tau
        a1 = (ref[i, 1] - speed[i, 1]) / tau
        forward[i] = (a0 * c[i] + a1 * s[i]) / g
        right[i] = (-a0 * s[i] + a1 * c[i]) / g
    return right, forward


tilt_tangents = compiled(_tilt_tangents)
