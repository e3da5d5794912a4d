"""The arithmetic of the local-to-WGS84 conversion (``GeoFrame.to_geodetic``), compiled in four
loops over the points, between which the transcendental functions stay numpy's.

The conversion runs for every vehicle at every telemetry tick; written as numpy expressions it
was some forty calls on arrays of a dozen elements. The loops do the same operations in the same
order (only +, -, *, / and sqrt, correctly rounded everywhere), so the results are the same to
the bit; hypot, ``g ** 3``, cbrt, arctan and arctan2 are left to numpy, whose SIMD loops may
round differently from the C library that compiled code calls. Closed-form ECEF to geodetic:
Heikkinen (1982).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled

FloatArray = NDArray[np.float64]

A = 6378137.0
F = 1 / 298.257223563
B = A * (1 - F)
E2 = F * (2 - F)
EP2 = (A**2 - B**2) / B**2
# The constant parts of the expressions, as Python evaluated them inside the numpy version.
_B2 = B**2
_F54 = 54 * B**2
_OM = 1 - E2
_K1 = E2 * (A**2 - B**2)
_E4 = E2**2
_E4X2 = 2 * E2**2
_A2H = A**2 / 2


def _to_ecef(
    north: FloatArray,
    east: FloatArray,
    up: FloatArray,
    origin: tuple[float, float, float],
    sl: float,
    cl: float,
    so: float,
    co: float,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """ECEF x, y, z of local points of the tangent plane at ``origin`` (its ECEF point) whose
    latitude and longitude have sines and cosines ``sl, cl, so, co``."""
    x0, y0, z0 = origin
    slco, clco, slso, clso = sl * co, cl * co, sl * so, cl * so
    n = north.size
    x, y, z = np.empty(n), np.empty(n), np.empty(n)
    for i in range(n):
        x[i] = x0 - so * east[i] - slco * north[i] + clco * up[i]
        y[i] = y0 + co * east[i] - slso * north[i] + clso * up[i]
        z[i] = z0 + cl * north[i] + sl * up[i]
    return x, y, z


def _heikkinen_g(z: FloatArray, p: FloatArray) -> FloatArray:
    """g of each point (``p`` is its distance from the axis)."""
    g = np.empty(z.size)
    for i in range(z.size):
        g[i] = p[i] * p[i] + _OM * (z[i] * z[i]) - _K1
    return g


def _cbrt_argument(z: FloatArray, p: FloatArray, g3: FloatArray) -> FloatArray:
    """1 + c + sqrt(c^2 + 2c) of each point, given g^3."""
    out = np.empty(z.size)
    for i in range(z.size):
        f = _F54 * (z[i] * z[i])
        c = _E4 * f * (p[i] * p[i]) / g3[i]
        out[i] = 1 + c + math.sqrt(c * c + 2 * c)
    return out


def _arctan_argument_and_height(
    z: FloatArray, p: FloatArray, g: FloatArray, s: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """The tangent of each point's latitude (before arctan) and its height, given g and s."""
    n = z.size
    tangent, height = np.empty(n), np.empty(n)
    for i in range(n):
        zi, pi, si = z[i], p[i], s[i]
        z2, p2 = zi * zi, pi * pi
        f = _F54 * z2
        w = si + 1 / si + 1
        pp = f / (3 * (w * w) * (g[i] * g[i]))
        q = math.sqrt(1 + _E4X2 * pp)
        r0 = -(pp * E2 * pi) / (1 + q) + math.sqrt(
            _A2H * (1 + 1 / q) - pp * _OM * z2 / (q * (1 + q)) - pp * p2 / 2
        )
        d = pi - E2 * r0
        d2 = d * d
        u = math.sqrt(d2 + z2)
        v = math.sqrt(d2 + _OM * z2)
        z0 = _B2 * zi / (A * v)
        height[i] = u * (1 - _B2 / (A * v))
        tangent[i] = (zi + EP2 * z0) / pi
    return tangent, height


# A zero divisor gives inf/NaN as in the numpy version (a point on the Earth's axis, say).
to_ecef = compiled(_to_ecef)
heikkinen_g = compiled(_heikkinen_g)
cbrt_argument = compiled(_cbrt_argument)
arctan_argument_and_height = compiled(_arctan_argument_and_height)
