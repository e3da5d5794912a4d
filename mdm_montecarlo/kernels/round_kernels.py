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
from mdm_montecarlo.kernels.entry_kernel import entry_row
from mdm_montecarlo.kernels.policy_step import DISC, IGNORE, LaneState, PolicyRules, nearest2
from mdm_montecarlo.kernels.round_state import Block, Events, Flight, Legs, Paths, Stepped

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]

CONTACT_EPS = 1e-9
"""Seconds: targets entered within this of the earliest entry are sensed in the same event."""
STOP_EPS = 1e-9
"""Seconds: a lane this close to its run's stop time is done."""


@compiled
def legs(
    state: LaneState,
    flight: Flight,
    lifetimes: FloatArray,
    speed: float,
    stepped: Stepped,
    out: Legs,
) -> float:
    """Per lane, written to the (n,) and (n, 2) arrays it is given: unit vector to the waypoint
    ``unit``, leg seconds ``leg``, seconds to the deadline ``left`` (SearchPolicy.deadline),
    horizon seconds ``horizon``. Returns the latest time any leg reaches (for the tracks'
    growth)."""
    waypoint, level, entered, blind_until = (
        state.waypoint,
        state.level,
        state.entered,
        state.blind_until,
    )
    position, time, stop = flight.position, flight.time, flight.stop
    lanes, runs = stepped.lanes, stepped.runs
    unit, leg, left, horizon = out
    until = 0.0
    for i in range(lanes.shape[0]):
        lane = lanes[i]
        t = time[lane]
        ox = waypoint[lane, 0] - position[lane, 0]
        oy = waypoint[lane, 1] - position[lane, 1]
        dist = math.sqrt(ox * ox + oy * oy)
        if dist > 0:
            unit[i, 0] = ox / dist
            unit[i, 1] = oy / dist
        else:
            unit[i, 0] = 0.0
            unit[i, 1] = 0.0
        leg[i] = dist / speed
        deadline = entered[lane] + lifetimes[level[lane]]
        if math.isfinite(blind_until[lane]) and level[lane] == 0:
            deadline = blind_until[lane]
        left[i] = deadline - t
        horizon[i] = max(min(leg[i], left[i], stop[runs[i]] - t), 0.0)
        until = max(until, t + horizon[i])
    return until


@compiled
def advance(
    state: LaneState,
    flight: Flight,
    stepped: Stepped,
    legs: Legs,
    paths: Paths,
    block: Block,
    rules: PolicyRules,
    events: Events,
) -> None:
    """Fly every lane to its next event: ``position`` and ``time`` are updated in place.

    ``eligible`` (n, m) comes in with the remembered targets of the lanes that check exactly
    cleared. Writes the lanes that reached their waypoint ``reached`` (n,), the contacts
    ``contacts`` (n, m) and the contacted targets' positions ``where`` (n, m, 2; only the
    contacts' entries are written: the policy step reads no other). ``entry`` (m,) holds one
    lane's entry times at a time. A lane's event depends on its own state and the targets
    only, so each lane is flown through before the next."""
    level, blind_until, waypoint = state.level, state.blind_until, state.waypoint
    memory, memory_count = state.memory, state.memory_count
    position, time = flight.position, flight.time
    lanes, runs = stepped.lanes, stepped.runs
    unit, leg, left, horizon = legs
    radii, detection_memory = rules.radii, rules.memory_rule
    speed, false_mask, appear = block.speed, block.false_mask, block.appear
    seg_start, seg_velocity, grid_dt = paths.seg_start, paths.seg_velocity, paths.grid_dt
    target_speed, moving = paths.grown, paths.moving
    eligible, entry, reached, contacts, where = events[:5]
    n, m = eligible.shape
    last = radii.shape[0] - 1
    redetect = rules.redetect != IGNORE and last > 0
    for i in range(n):
        lane = lanes[i]
        lvl = level[lane]
        t = time[lane]
        start_x = position[lane, 0]
        start_y = position[lane, 1]
        vx = unit[i, 0] * speed
        vy = unit[i, 1] * speed
        detecting = lvl < last
        ignored = detecting and t < blind_until[lane]
        if detection_memory == DISC and detecting and not ignored:
            # Only where it decides: the distance to the remembered targets.
            ignored = nearest2(memory, memory_count[lane], lane, start_x, start_y) < radii[lvl] ** 2
        for j in range(m):
            if ignored or (lvl == last and false_mask[j]):
                eligible[i, j] = False
        row = runs[i] if moving else 0
        entry_row(
            start_x,
            start_y,
            vx,
            vy,
            horizon[i],
            t,
            row,
            radii[lvl],
            eligible,
            i,
            appear,
            seg_start,
            seg_velocity,
            grid_dt,
            target_speed,
            moving,
            entry,
        )
        soonest = np.inf
        for j in range(m):
            soonest = min(soonest, entry[j])
        hit = soonest <= horizon[i]
        new_t = t + (soonest if hit else horizon[i])
        if not hit and horizon[i] == left[i]:
            # Land exactly on a deadline so the policy sees the index run out (no float creep).
            new_t = t + left[i]
        step = soonest if hit else horizon[i]
        reached[i] = not hit and horizon[i] >= leg[i]
        if reached[i]:
            position[lane, 0] = waypoint[lane, 0]
            position[lane, 1] = waypoint[lane, 1]
        else:
            position[lane, 0] = start_x + vx * step
            position[lane, 1] = start_y + vy * step
        time[lane] = new_t
        if redetect and lvl == last:  # read by the step where it decides (policy_step)
            detect(i, lane, row, radii[last - 1], flight, block, paths, events)
        if not hit:
            for j in range(m):
                contacts[i, j] = False
            continue
        k = math.floor(new_t / grid_dt + NODE_EPS) if moving else 0
        offset = new_t - k * grid_dt if moving else 0.0
        for j in range(m):
            contacts[i, j] = entry[j] <= soonest + CONTACT_EPS
            if contacts[i, j]:
                where[i, j, 0] = seg_velocity[row, k, j, 0] * offset + seg_start[row, k, j, 0]
                where[i, j, 1] = seg_velocity[row, k, j, 1] * offset + seg_start[row, k, j, 1]


@compiled
def detect(
    i: int,
    lane: int,
    row: int,
    radius: float,
    flight: Flight,
    block: Block,
    paths: Paths,
    events: Events,
) -> None:
    """Row ``i`` of ``events.detections``: the appeared targets (false ones too) strictly
    within the detection ``radius`` of last-level ``lane`` where and when it now is (its
    targets' paths: ``row``), their positions written to ``events.where``."""
    seg_start, seg_velocity, grid_dt = paths.seg_start, paths.seg_velocity, paths.grid_dt
    detections, where = events.detections, events.where
    t = flight.time[lane]
    k = math.floor(t / grid_dt + NODE_EPS) if paths.moving else 0
    offset = t - k * grid_dt if paths.moving else 0.0
    r2 = radius * radius
    for j in range(detections.shape[1]):
        x = seg_velocity[row, k, j, 0] * offset + seg_start[row, k, j, 0]
        y = seg_velocity[row, k, j, 1] * offset + seg_start[row, k, j, 1]
        north = flight.position[lane, 0] - x
        east = flight.position[lane, 1] - y
        detections[i, j] = block.appear[j] <= t and north * north + east * east < r2
        if detections[i, j]:
            where[i, j, 0] = x
            where[i, j, 1] = y


@compiled
def record(
    flight: Flight,
    stepped: Stepped,
    confirmed: BoolArray,
    confirmations: BoolArray,
    block: Block,
) -> None:
    """Keep each lane's first confirmation time of each real target, move the stop time of the
    runs that confirmed (the latest time a confirmation can still change T_nc or T_S: the
    team's last first confirmation, within [duration, cap]) and retire the lanes past it.
    ``confirmations`` (n, m) are the new ones; only the ``confirmed`` lanes (n,) have any.
    ``gone`` (runs, m): when a target left the area (inf: never, or T_S counts confirmations
    only); a target is done at its confirmation or departure, whichever is first."""
    first, stop, gone, active, time = (
        flight.first,
        flight.stop,
        flight.gone,
        flight.active,
        flight.time,
    )
    lanes, runs, real = stepped.lanes, stepped.runs, block.real
    n_vehicles, duration, cap = block.n_vehicles, block.duration, block.cap
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
            team = gone[run, j]
            for v in range(n_vehicles):
                team = min(team, first[run * n_vehicles + v, j])
            bound = max(bound, team)
        stop[run] = min(max(bound, duration), cap)
    for i in range(lanes.shape[0]):
        active[lanes[i]] = time[lanes[i]] < stop[runs[i]] - STOP_EPS
