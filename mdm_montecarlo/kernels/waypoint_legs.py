"""Compiled (numba) legs of the waypoint swarm (mdm_montecarlo.engines.waypoint_swarm): a particle's
flight from one waypoint to the next, solved once when the leg starts instead of step by step.

A particle flies straight to its waypoint, and nothing it meets on the way changes that: its
iteration ends only on arrival. So when a leg starts its whole course is known: the steps of
``update_interval`` it takes (``swarm_kernels.fly``'s arithmetic, step by step, so the arrival
step and position are the time-stepped engine's to the bit) and the targets it confirms on the
way (``SwarmSensors.confirm``'s closed form on each step's segment, for the targets that come
near the leg at all). The engine then jumps from one step with arrivals to the next.

A confirmation found here may come after another vehicle of the run has already confirmed the
same target on its own leg; the time-stepped engine never solves such a pair (the run knew the
target). ``known_step`` keeps the earliest step at which each run confirms each target, and the
engine keeps a vehicle's confirmation only where it was made in that step (``keep_first``).
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled
from mdm_core.world.targets import NODE_EPS
from mdm_montecarlo.kernels.entry_kernel import disc_entry
from mdm_montecarlo.kernels.swarm_kernels import signal

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]

MARGIN = 1.0
"""Metres added to the distance within which a leg's targets are solved (rounding margin)."""


@compiled
def walk_legs(
    starting: IntArray,
    position: FloatArray,
    waypoint: FloatArray,
    begin: int,
    times: FloatArray,
    dt: float,
    distance: float,
    area: FloatArray,
    n_vehicles: int,
    seg_start: FloatArray,
    seg_velocity: FloatArray,
    grid_dt: float,
    moving: bool,
    top_speed: float,
    appear: FloatArray,
    real: BoolArray,
    radius: float,
    known_step: IntArray,
    conf_time: FloatArray,
    conf_step: IntArray,
    arrival_step: IntArray,
    arrival: FloatArray,
) -> None:
    """The legs of the ``starting`` particles (flat indices run * n_vehicles + vehicle), which
    start at step ``begin`` from ``position`` (particles, 2) towards ``waypoint``: step q flies
    from times[q - 1] to times[q] (``dt`` apart), at most ``distance`` per step, clipped to ``area``, until
    the waypoint is within 1e-6 m or the last step (len(times) - 1) is flown. Writes each
    particle's ``arrival_step`` (len(times) if it does not arrive) and ``arrival`` position,
    and for every real target that the run does not know by step ``begin`` and whose
    confirmation disc of ``radius`` the particle enters: ``conf_time``, ``conf_step``
    (particles, targets) and the run's earliest ``known_step`` (runs, targets), in place.

    Targets follow ``seg_start`` / ``seg_velocity`` (TargetTracks.segments, drawn to the last
    step; row 0 for fixed targets) at most at ``top_speed``; only those that come within
    ``radius`` of the leg's line are solved."""
    last = times.shape[0] - 1
    m = appear.shape[0]
    legs = starting.shape[0]
    x = np.empty(legs)
    y = np.empty(legs)
    wx = np.empty(legs)
    wy = np.empty(legs)
    gap = np.empty(legs)
    arrived = np.full(legs, last + 1)
    candidate = np.empty((legs, m), dtype=np.intp)
    count = np.zeros(legs, dtype=np.intp)
    for i in range(legs):
        p = starting[i]
        run = p // n_vehicles
        x[i] = position[p, 0]
        y[i] = position[p, 1]
        wx[i] = waypoint[p, 0]
        wy[i] = waypoint[p, 1]
        gap[i] = math.sqrt((wx[i] - x[i]) * (wx[i] - x[i]) + (wy[i] - y[i]) * (wy[i] - y[i]))
        # At most this many steps: the leg's length over the step, and one for the rounding.
        steps = min(last - begin, int(gap[i] / distance) + 2)
        reach = radius + top_speed * steps * dt + MARGIN
        for j in range(m):
            if not real[j] or known_step[run, j] <= begin or appear[j] > times[begin + steps]:
                continue
            tx, ty = _target_at(seg_start, seg_velocity, grid_dt, moving, run, j, times[begin])
            if _segment_distance(tx, ty, x[i], y[i], wx[i], wy[i]) <= reach:
                candidate[i, count[i]] = j
                count[i] += 1
        if count[i] > 0:
            _confirm_on_leg(
                p,
                x[i],
                y[i],
                wx[i],
                wy[i],
                gap[i],
                candidate[i, : count[i]],
                begin,
                times,
                dt,
                distance,
                area,
                n_vehicles,
                seg_start,
                seg_velocity,
                grid_dt,
                moving,
                appear,
                radius,
                known_step,
                conf_time,
                conf_step,
            )
    _fly(x, y, wx, wy, gap, arrived, distance, area[0], area[1], begin, last)
    for i in range(legs):
        p = starting[i]
        arrival_step[p] = arrived[i]
        arrival[p, 0] = x[i]
        arrival[p, 1] = y[i]


@compiled
def _fly(
    x: FloatArray,
    y: FloatArray,
    wx: FloatArray,
    wy: FloatArray,
    gap: FloatArray,
    arrived: IntArray,
    distance: float,
    width: float,
    height: float,
    begin: int,
    last: int,
) -> None:
    """Every leg (x, y) -> (wx, wy) with distance ``gap`` left, flown step by step from step
    ``begin`` as swarm_kernels.fly flies it, until each is within 1e-6 m of its waypoint
    (``arrived``: that step) or step ``last``; x, y, gap and arrived in place. The legs are
    the inner loop, without branches, so the compiler runs several at once."""
    flying = x.shape[0]
    q = begin
    while flying > 0 and q < last:
        q += 1
        flying = 0
        for i in range(x.shape[0]):
            going = arrived[i] > last
            nx, ny, left = _step(x[i], y[i], wx[i], wy[i], gap[i], distance, width, height)
            x[i] = nx if going else x[i]
            y[i] = ny if going else y[i]
            gap[i] = left if going else gap[i]
            now = going and left <= 1e-6
            arrived[i] = q if now else arrived[i]
            flying += going and not now


@compiled
def _confirm_on_leg(
    p: int,
    x: float,
    y: float,
    wx: float,
    wy: float,
    gap: float,
    candidates: IntArray,
    begin: int,
    times: FloatArray,
    dt: float,
    distance: float,
    area: FloatArray,
    n_vehicles: int,
    seg_start: FloatArray,
    seg_velocity: FloatArray,
    grid_dt: float,
    moving: bool,
    appear: FloatArray,
    radius: float,
    known_step: IntArray,
    conf_time: FloatArray,
    conf_step: IntArray,
) -> None:
    """The confirmations of particle p on its leg from (x, y) to (wx, wy), step by step (the
    steps as _fly flies them), for its ``candidates`` targets; in place."""
    last = times.shape[0] - 1
    run = p // n_vehicles
    q = begin
    while q < last:
        q += 1
        nx, ny, left = _step(x, y, wx, wy, gap, distance, area[0], area[1])
        for j in candidates:
            if conf_step[p, j] <= last:
                continue
            entry = _entry(
                x,
                y,
                nx - x,
                ny - y,
                seg_start,
                seg_velocity,
                grid_dt,
                moving,
                run,
                j,
                times[q - 1],
                dt,
                appear[j],
                radius,
            )
            if entry != np.inf:
                conf_time[p, j] = times[q - 1] + entry
                conf_step[p, j] = q
                known_step[run, j] = min(known_step[run, j], q)
        x = nx
        y = ny
        gap = left
        if gap <= 1e-6:
            return


@partial(compiled, inline=True)
def _step(
    x: float,
    y: float,
    wx: float,
    wy: float,
    gap: float,
    distance: float,
    width: float,
    height: float,
) -> tuple[float, float, float]:
    """One step of swarm_kernels.fly from (x, y) towards (wx, wy), ``gap`` away: at most
    ``distance``, clipped to the area (0 .. width, 0 .. height). Returns the new position and
    fly's distance left, which is the next step's gap as well."""
    scale = min(1.0, distance / max(gap, 1e-12))
    nx = min(max(x + (wx - x) * scale, 0.0), width)
    ny = min(max(y + (wy - y) * scale, 0.0), height)
    return nx, ny, math.sqrt((wx - nx) * (wx - nx) + (wy - ny) * (wy - ny))


@compiled
def _target_at(
    seg_start: FloatArray,
    seg_velocity: FloatArray,
    grid_dt: float,
    moving: bool,
    run: int,
    j: int,
    t: float,
) -> tuple[float, float]:
    """Target j of the run at time t (TargetTracks.motion's arithmetic)."""
    if not moving:
        return seg_start[0, 0, j, 0], seg_start[0, 0, j, 1]
    k = math.floor(t / grid_dt + NODE_EPS)
    offset = t - k * grid_dt
    return (
        seg_velocity[run, k, j, 0] * offset + seg_start[run, k, j, 0],
        seg_velocity[run, k, j, 1] * offset + seg_start[run, k, j, 1],
    )


@compiled
def _segment_distance(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> float:
    """Distance from point p to the segment a-b."""
    dx = bx - ax
    dy = by - ay
    length2 = dx * dx + dy * dy
    u = 0.0 if length2 == 0 else min(max(((px - ax) * dx + (py - ay) * dy) / length2, 0.0), 1.0)
    ex = ax + u * dx - px
    ey = ay + u * dy - py
    return math.sqrt(ex * ex + ey * ey)


@compiled
def _entry(
    x: float,
    y: float,
    step_x: float,
    step_y: float,
    seg_start: FloatArray,
    seg_velocity: FloatArray,
    grid_dt: float,
    moving: bool,
    run: int,
    j: int,
    t: float,
    dt: float,
    appear: float,
    radius: float,
) -> float:
    """Seconds after t at which the step (x, y) -> (x + step_x, y + step_y), flown in dt,
    enters the disc of target j (inf: not in this step): pair_entry_times' arithmetic on
    SwarmSensors.confirm's arguments (velocity step / dt, the target where motion(t) puts it,
    not before it appears)."""
    if moving:
        k = math.floor(t / grid_dt + NODE_EPS)
        offset = t - k * grid_dt
        tvx = seg_velocity[run, k, j, 0]
        tvy = seg_velocity[run, k, j, 1]
        tx = tvx * offset + seg_start[run, k, j, 0]
        ty = tvy * offset + seg_start[run, k, j, 1]
    else:
        tvx = 0.0
        tvy = 0.0
        tx = seg_start[0, 0, j, 0]
        ty = seg_start[0, 0, j, 1]
    north = x - tx
    east = y - ty
    dist2 = north * north + east * east
    lo = max(appear - t, 0.0)
    if lo > dt:
        return np.inf
    return disc_entry(
        north, east, step_x / dt - tvx, step_y / dt - tvy, dist2 - radius * radius, lo, dt
    )


@compiled
def read_arrivals(
    arrived: IntArray,
    position: FloatArray,
    seg_start: FloatArray,
    seg_velocity: FloatArray,
    grid_dt: float,
    moving: bool,
    appear: FloatArray,
    t: float,
    radius: float,
    near: float,
    known_step: IntArray,
    now: int,
    unread_known: bool,
    n_vehicles: int,
    fitness: FloatArray,
    source: IntArray,
) -> None:
    """swarm_kernels.sense's reading for the ``arrived`` particles (flat indices) alone, at
    ``position`` (particles, 2), the targets where TargetTracks.motion puts them at time t:
    the strongest exp(-d / radius) above THRESHOLD of a present target within ``radius``, the
    targets the run confirmed by step ``now`` left out where ``unread_known``; ``fitness`` and
    ``source`` (particles,) in place (0 and -1 if none)."""
    m = appear.shape[0]
    for p in arrived:
        run = p // n_vehicles
        best = 0.0
        found = -1
        for k in range(m):
            tx, ty = _target_at(seg_start, seg_velocity, grid_dt, moving, run, k, t)
            dx = tx - position[p, 0]
            dy = ty - position[p, 1]
            gap = dx * dx + dy * dy
            known = unread_known and known_step[run, k] <= now
            if gap < near and appear[k] <= t and not known:
                strength = signal(gap, radius)
                if strength > best:
                    best = strength
                    found = k
        fitness[p] = best
        source[p] = found


@compiled
def forget_confirmed(
    fitness: FloatArray, source: IntArray, known_step: IntArray, now: int, n_vehicles: int
) -> None:
    """swarm_kernels.forget_known with the run's confirmations by step ``now``: bests
    (particles,) whose source target the run has confirmed get fitness 0 and source -1."""
    for p in range(fitness.shape[0]):
        if source[p] >= 0 and known_step[p // n_vehicles, source[p]] <= now:
            fitness[p] = 0.0
            source[p] = -1


@compiled
def keep_first(
    conf_time: FloatArray, conf_step: IntArray, known_step: IntArray, end: int, n_vehicles: int
) -> FloatArray:
    """(particles, targets) first confirmation times as the time-stepped engine records them:
    a vehicle's confirmation made in the step at which its run first confirmed the target, by
    step ``end``; inf elsewhere."""
    n, m = conf_time.shape
    first = np.full((n, m), np.inf)
    for p in range(n):
        run = p // n_vehicles
        for j in range(m):
            if conf_step[p, j] <= end and conf_step[p, j] == known_step[run, j]:
                first[p, j] = conf_time[p, j]
    return first
