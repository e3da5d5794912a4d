"""Compiled (numba) entry times of a lane into every target's sensor disc along its leg.

The same arithmetic as ``mdm_core.world.first_entry_time`` (closed form, boundary crossing,
reach bound), applied piece by piece between the nodes of a moving target's path grid, but
fused per lane: one pass over the lane's targets per piece instead of a dozen numpy passes over
(lanes, targets) temporaries, which were a third of the engine's time (docs/model.md, "Speed
of reproduce"). Every operation is the numpy version's, in its order, so results are
bit-identical (tests/montecarlo/test_entry_kernel.py compares the two on random legs). The
round (``round_kernels.advance``) solves one lane at a time into one row of m times, reused from
lane to lane, rather than into a (lanes, targets) array filled with inf every round.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled
from mdm_core.world.sensors import REACH_SLACK
from mdm_core.world.targets import NODE_EPS

FloatArray = NDArray[np.float64]


@compiled
def disc_entry(
    north: float, east: float, rvx: float, rvy: float, c: float, lo: float, span: float
) -> float:
    """The first time in [``lo``, ``span``] at which a point (``north``, ``east``) from a disc's
    centre, moving at (``rvx``, ``rvy``) relative to it, is inside the disc (``c``: its squared
    distance less the squared radius); inf where it is not. first_entry_time's closed form and
    boundary crossing, in its order of operations."""
    a = rvx * rvx + rvy * rvy
    b = north * rvx + east * rvy
    disc = b * b - a * c
    if a > 1e-12:
        root = math.sqrt(max(disc, 0.0))
        s1 = (-b - root) / a
        s2 = (-b + root) / a
        hit = disc > 0
    else:
        s1 = -np.inf
        s2 = np.inf
        hit = c < 0
    first = max(s1, lo)
    return first if hit and first < s2 and first <= span else np.inf


@partial(compiled, inline=True)
def entry_row(
    start_x: float,
    start_y: float,
    vx: float,
    vy: float,
    leg: float,
    t: float,
    row: int,
    radius: float,
    eligible: NDArray[np.bool_],
    i: int,
    appear: FloatArray,
    seg_start: FloatArray,
    seg_velocity: FloatArray,
    grid_dt: float,
    target_speed: float,
    moving: bool,
    out: FloatArray,
) -> None:
    """Seconds after ``t`` at which a lane, flying from (``start_x``, ``start_y``) at (``vx``,
    ``vy``) for ``leg`` seconds, first enters each target's sensor disc of ``radius``, written
    to ``out`` (m,) (inf: not within the leg, or not eligible: row ``i`` of ``eligible`` (n, m),
    not a view of it, which would cost a reference count per lane). ``seg_start`` and
    ``seg_velocity`` are ``TargetTracks.segments`` drawn up to the latest leg end; ``row`` is the
    lane's run (0 for fixed targets).

    Moving targets go straight between the nodes of their path grid, so a leg that crosses
    nodes is solved piece by piece, stopping at the first piece with a contact (only the
    earliest contacts count).

    Compiled into its callers (``inline``): called, it would take and release a reference to
    each of its five arrays, atomically, once per lane and event (a fifth of the batch rows'
    CPU time when tried).
    """
    m = eligible.shape[1]
    for j in range(m):
        out[j] = np.inf
    vehicle_speed = math.sqrt(vx * vx + vy * vy)
    r2 = radius * radius
    begin = 0.0
    now = t
    while True:
        if moving:
            k = math.floor(now / grid_dt + NODE_EPS)
            end = min((k + 1.0) * grid_dt - t, leg)
            offset = now - k * grid_dt
        else:
            k = 0
            end = leg
            offset = 0.0
        span = end - begin
        sx = start_x + vx * begin
        sy = start_y + vy * begin
        reach = radius + (vehicle_speed + target_speed) * span + REACH_SLACK
        found = False
        for j in range(m):
            if not eligible[i, j]:
                continue
            tvx = seg_velocity[row, k, j, 0]
            tvy = seg_velocity[row, k, j, 1]
            px = tvx * offset + seg_start[row, k, j, 0]
            py = tvy * offset + seg_start[row, k, j, 1]
            north = sx - px
            east = sy - py
            dist2 = north * north + east * east
            lo = max(appear[j] - now, 0.0)
            if not (dist2 <= reach * reach and lo <= span):
                continue
            first = disc_entry(north, east, vx - tvx, vy - tvy, dist2 - r2, lo, span)
            if first != np.inf:
                out[j] = first + begin
                found = True
        if found or end >= leg:
            break
        begin = end
        now = t + begin
