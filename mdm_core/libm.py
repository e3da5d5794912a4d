"""Elementwise C-library (libm) versions of numpy's transcendental functions.

numpy picks a SIMD loop for tan, exp, log and power by CPU: on a CPU with AVX-512 they round
differently from the C library in the last bit for about 0.5-5 % of arguments (measured with
numpy 2.4 on an AMD EPYC: tan 0.5 %, pow 5 %), elsewhere they are the C library's. Sampling
with them made a seeded draw depend on the machine, and the engine's compiled kernels (numba,
which calls the C library) agree with numpy only where numpy does. These take the C library's
value for every element (Python's math module is libm), so a seeded draw is the same on every
machine with the same C library and the same as the compiled kernels'. They cost ~0.1 us per element: for the
policy's few draws per step, not for large arrays.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def _each(function: Callable[[float], float], x: ArrayLike) -> FloatArray:
    values = np.asarray(x, dtype=float)
    out = np.fromiter(map(function, values.ravel().tolist()), float, count=values.size)
    return out.reshape(values.shape)


def tan(x: ArrayLike) -> FloatArray:
    """math.tan of every element."""
    return _each(math.tan, x)


def sin(x: ArrayLike) -> FloatArray:
    """math.sin of every element."""
    return _each(math.sin, x)


def cos(x: ArrayLike) -> FloatArray:
    """math.cos of every element."""
    return _each(math.cos, x)


def exp(x: ArrayLike) -> FloatArray:
    """math.exp of every element."""
    return _each(math.exp, x)


def power(x: ArrayLike, exponent: float) -> FloatArray:
    """Every element to the float ``exponent`` with the C library's pow (x ** exponent)."""
    return _each(lambda value: value**exponent, x)
