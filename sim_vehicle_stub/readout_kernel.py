"""What each active sensor reads from the world's contacts, compiled: the strongest signal of a
target it can see, and the targets that came into its range this tick (its range memory updated
in the same pass). One loop instead of some ten numpy calls on a dozen vehicles' rows; maxima
and comparisons only, so exactly the values of the numpy expressions it replaces.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]


def _readout(
    mask: BoolArray,
    strength: FloatArray,
    present: BoolArray,
    confirms: BoolArray,
    false_mask: BoolArray,
    in_range: BoolArray,
    on: IntArray,
    sensor: IntArray,
) -> tuple[FloatArray, BoolArray]:
    """For row r (vehicle ``on[r]``, its sensor ``sensor[r]``): the largest strength over present
    targets that sensor sees (a confirming sensor no false ones; 0 when none, NaN when one is
    NaN), and which targets of ``mask`` (in range) were not in ``in_range`` (n, m, sensors),
    which becomes ``mask``."""
    rows, m = mask.shape
    signal = np.empty(rows)
    entered = np.empty((rows, m), dtype=np.bool_)
    for r in range(rows):
        best = 0.0
        i, s = on[r], sensor[r]
        for k in range(m):
            value = strength[r, k] if present[k] and not (confirms[r] and false_mask[k]) else 0.0
            if value > best or math.isnan(value):
                best = value
            entered[r, k] = mask[r, k] and not in_range[i, k, s]
            in_range[i, k, s] = mask[r, k]
        signal[r] = best
    return signal, entered


readout = compiled(_readout)
