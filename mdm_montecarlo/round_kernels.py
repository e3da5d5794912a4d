"""One round of the batch engine compiled (numba): every active lane flies to its next event.

A round was some sixty numpy calls on (lanes,) and (lanes, targets) temporaries around the
compiled entry kernel and the compiled policy step (docs/model.md, "Speed of reproduce"). Here
three loops over the lanes do the same arithmetic in the same order:

- ``legs``: the straight leg to the waypoint, the level's deadline and the horizon of the leg
  (the earliest of waypoint, deadline and the run's stop time);
- ``advance``: which targets each lane may sense (the policy's own ignore rules: blind period,
  remembered disc, false targets for the confirmation sensor), the entry times, the event it
  reaches first, its new time and position, the contacts and where the contacted targets are.

- ``record``: the first confirmation times, the runs' stop times and which lanes go on.

``block_rounds`` calls them round after round; only the growth of the tracks stays in numpy.
Results are bit-identical to the numpy round (tests/montecarlo/test_determinism.py and the
reproduce comparison in docs/model.md).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled
from mdm_core.world.targets import NODE_EPS
from mdm_montecarlo.compiled_step import DISC, nearest2
from mdm_montecarlo.entry_kernel import entry_times_of

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]

CONTACT_EPS = 1e-9
"""Seconds: targets entered within this of the earliest entry are sensed in the same event."""
STOP_EPS = 1e-9
"""Seconds: a lane this close to its run's stop time is done."""


@compiled
def legs(
    waypoint: FloatArray,
    position: FloatArray,
    time: FloatArray,
    level: IntArray,
    entered: FloatArray,
    blind_until: FloatArray,
    lifetimes: FloatArray,
    stop: FloatArray,
    lanes: IntArray,
    runs: IntArray,
    speed: float,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, float]:
    """Per lane: unit vector to the waypoint (n, 2), leg seconds, seconds to the deadline
    (SearchPolicy.deadline), horizon seconds; and the latest time any leg reaches (for the
    tracks' growth)."""
    n = lanes.shape[0]
    unit = np.zeros((n, 2))
    leg = np.empty(n)
    left = np.empty(n)
    horizon = np.empty(n)
    until = 0.0
    for i in range(n):
        lane = lanes[i]
        t = time[lane]
        ox = waypoint[lane, 0] - position[lane, 0]
        oy = waypoint[lane, 1] - position[lane, 1]
        dist = math.sqrt(ox * ox + oy * oy)
        if dist > 0:
            unit[i, 0] = ox / dist
            unit[i, 1] = oy / dist
        leg[i] = dist / speed
        deadline = entered[lane] + lifetimes[level[lane]]
        if math.isfinite(blind_until[lane]) and level[lane] == 0:
            deadline = blind_until[lane]
        left[i] = deadline - t
        horizon[i] = max(min(leg[i], left[i], stop[runs[i]] - t), 0.0)
        until = max(until, t + horizon[i])
    return unit, leg, left, horizon, until


@compiled
def advance(
    level: IntArray,
    blind_until: FloatArray,
    memory: FloatArray,
    memory_count: IntArray,
    position: FloatArray,
    time: FloatArray,
    waypoint: FloatArray,
    lanes: IntArray,
    runs: IntArray,
    unit: FloatArray,
    leg: FloatArray,
    left: FloatArray,
    horizon: FloatArray,
    eligible: BoolArray,
    radii: FloatArray,
    detection_memory: int,
    false_mask: BoolArray,
    appear: FloatArray,
    seg_start: FloatArray,
    seg_velocity: FloatArray,
    grid_dt: float,
    target_speed: float,
    moving: bool,
    speed: float,
) -> tuple[BoolArray, BoolArray, FloatArray]:
    """Fly every lane to its next event: ``position`` and ``time`` are updated in place.

    ``eligible`` (n, m) comes in with the remembered targets of the lanes that check exactly
    cleared. Returns the lanes that reached their waypoint, the contacts (n, m) and the
    contacted targets' positions (n, m, 2; only the contacts' entries are written: the policy
    step reads no other)."""
    n, m = eligible.shape
    last = radii.shape[0] - 1
    start = np.empty((n, 2))
    velocity = np.empty((n, 2))
    radius = np.empty(n)
    t = np.empty(n)
    for i in range(n):
        lane = lanes[i]
        lvl = level[lane]
        t[i] = time[lane]
        start[i, 0] = position[lane, 0]
        start[i, 1] = position[lane, 1]
        velocity[i, 0] = unit[i, 0] * speed
        velocity[i, 1] = unit[i, 1] * speed
        radius[i] = radii[lvl]
        detecting = lvl < last
        ignored = detecting and t[i] < blind_until[lane]
        if detection_memory == DISC:
            near = nearest2(memory, memory_count[lane], lane, start[i, 0], start[i, 1])
            ignored = ignored or (detecting and near < radii[lvl] ** 2)
        for j in range(m):
            if ignored or (lvl == last and false_mask[j]):
                eligible[i, j] = False
    entry = entry_times_of(
        start,
        velocity,
        horizon,
        t,
        runs,
        radius,
        eligible,
        appear,
        seg_start,
        seg_velocity,
        grid_dt,
        target_speed,
        moving,
    )
    reached = np.zeros(n, dtype=np.bool_)
    contacts = np.zeros((n, m), dtype=np.bool_)
    where = np.empty((n, m, 2))
    for i in range(n):
        lane = lanes[i]
        soonest = np.inf
        for j in range(m):
            soonest = min(soonest, entry[i, j])
        hit = soonest <= horizon[i]
        new_t = t[i] + (soonest if hit else horizon[i])
        if not hit and horizon[i] == left[i]:
            # Land exactly on a deadline so the policy sees the index run out (no float creep).
            new_t = t[i] + left[i]
        step = soonest if hit else horizon[i]
        if not hit and horizon[i] >= leg[i]:
            reached[i] = True
            position[lane, 0] = waypoint[lane, 0]
            position[lane, 1] = waypoint[lane, 1]
        else:
            position[lane, 0] = start[i, 0] + velocity[i, 0] * step
            position[lane, 1] = start[i, 1] + velocity[i, 1] * step
        time[lane] = new_t
        if not hit:
            continue
        row = runs[i] if moving else 0
        k = math.floor(new_t / grid_dt + NODE_EPS) if moving else 0
        offset = new_t - k * grid_dt if moving else 0.0
        for j in range(m):
            contacts[i, j] = entry[i, j] <= soonest + CONTACT_EPS
            if contacts[i, j]:
                where[i, j, 0] = seg_velocity[row, k, j, 0] * offset + seg_start[row, k, j, 0]
                where[i, j, 1] = seg_velocity[row, k, j, 1] * offset + seg_start[row, k, j, 1]
    return reached, contacts, where


@compiled
def record(
    first: FloatArray,
    stop: FloatArray,
    active: BoolArray,
    confirmed: BoolArray,
    confirmations: BoolArray,
    lanes: IntArray,
    runs: IntArray,
    time: FloatArray,
    real: BoolArray,
    n_vehicles: int,
    duration: float,
    cap: float,
) -> None:
    """Keep each lane's first confirmation time of each real target, move the stop time of the
    runs that confirmed (the latest time a confirmation can still change T_nc or T_S: the
    team's last first confirmation, within [duration, cap]) and retire the lanes past it.
    ``confirmations`` (n, m) are the new ones; only the ``confirmed`` lanes (n,) have any."""
    m = first.shape[1]
    changed = np.zeros(stop.shape[0], dtype=np.bool_)
    for i in range(lanes.shape[0]):
        if not confirmed[i]:
            continue
        lane = lanes[i]
        for j in range(m):
            if confirmations[i, j] and real[j]:
                first[lane, j] = min(first[lane, j], time[lane])
                changed[runs[i]] = True
    for run in np.flatnonzero(changed):
        bound = -np.inf
        for j in range(m):
            if not real[j]:
                continue
            team = np.inf
            for v in range(n_vehicles):
                team = min(team, first[run * n_vehicles + v, j])
            bound = max(bound, team)
        stop[run] = min(max(bound, duration), cap)
    for i in range(lanes.shape[0]):
        active[lanes[i]] = time[lanes[i]] < stop[runs[i]] - STOP_EPS
