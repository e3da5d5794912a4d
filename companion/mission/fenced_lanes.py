"""A lawnmower sweep kept inside the guidance fence: each lane cut to the part inside it.

The plan (mdm_core.search.lawnmower) lays lanes from one edge of a cell to the other, and a
cell's edge can be the area's edge, outside a site's fence (field-duebendorf's fence is 40-60 m
inside its box, and the guidance fence another ``site.fence_inset`` in). Here each lane is cut
to the convex guidance fence; a lane wholly outside it is dropped; the turn between two lanes
is then the straight leg from one cut end to the next cut start, inside the fence because the
fence is convex (a site fence must be: mdm_core.world.fence_planes).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from companion.geofence import Geofence

FloatArray = NDArray[np.float64]

SHORTEST_LANE_M = 1.0
"""A lane that keeps less than this inside the fence is dropped (a corner grazed)."""


def fenced_lanes(sweep: FloatArray, fence: Geofence) -> FloatArray:
    """``sweep`` (2 lanes, 2): lane k from ``sweep[2k]`` to ``sweep[2k + 1]``, cut to ``fence``
    (same direction, lanes in the same order); ValueError if no lane is left."""
    kept: list[FloatArray] = []
    for k in range(len(sweep) // 2):
        cut = _clip(sweep[2 * k], sweep[2 * k + 1], fence.vertices)
        if cut is not None:
            kept.extend(cut)
    if not kept:
        raise ValueError(
            "no lane of this vehicle's cell lies inside the guidance fence (the site's fence "
            "less site.fence_inset): the cell is outside the fence"
        )
    out = np.array(kept)
    if math.dist(out[1], sweep[0]) < math.dist(out[0], sweep[0]):
        # An odd number of lanes dropped before the first kept one: every kept lane turned
        # round, so the sweep still begins at the plan's corner (the alternation is kept).
        out = out.reshape(-1, 2, 2)[:, ::-1].reshape(-1, 2)
    return out


def _clip(a: FloatArray, b: FloatArray, polygon: FloatArray) -> tuple[FloatArray, ...] | None:
    """The part of segment a-b inside the convex ``polygon`` (Cyrus-Beck), or None."""
    d = b - a
    centre = polygon.mean(axis=0)
    low, high = 0.0, 1.0
    for p, q in zip(polygon, np.roll(polygon, -1, axis=0), strict=True):
        edge = q - p
        normal = np.array([-edge[1], edge[0]])
        if float(normal @ (centre - p)) < 0.0:
            normal = -normal  # the inward normal
        start = float(normal @ (a - p))  # > 0: a on the inner side of this edge
        rate = float(normal @ d)
        if rate == 0.0:
            if start < 0.0:
                return None
            continue
        t = -start / rate
        if rate > 0.0:
            low = max(low, t)
        else:
            high = min(high, t)
        if low > high:
            return None
    if (high - low) * float(np.hypot(*d)) < SHORTEST_LANE_M:
        return None
    return a + low * d, a + high * d
