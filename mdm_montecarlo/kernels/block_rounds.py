"""The batch engine's rounds, compiled (numba) into one loop: a block runs in a few calls.

A round moves every active lane to its next event: ``legs``, the remembered targets
(``remembered.eligible``), ``advance``, the policy step and its memory update
(``compiled_step``), ``record``. Called from Python, each round cost two dozen numpy calls
and six kernel dispatches around those loops, about a sixth of the MDM rows' CPU time over
their 18 000 rounds (benchmarks/README.md, "2026-11-23 to 2026-11-26: reproduce's speed, change
by change"). Here the same kernels run in the same
order on the same arrays, round after round, and the loop only returns when the block is done
or a dynamic target's path must grow (its draws are numpy's; the caller grows it and calls
again, which redoes the round from its start: nothing was changed yet).

Which top speed each step sees is the Python loop's: the remembered targets' windows are
checked against the speed of the paths drawn before the round's growth, the entry times
against the speed after it (``visible`` and ``grown``).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled
from mdm_core.world.targets import NODE_EPS
from mdm_montecarlo.kernels.compiled_step import CONFIRMED, EXACT, remember_confirmed, step_lanes
from mdm_montecarlo.kernels.remembered import eligible
from mdm_montecarlo.kernels.round_kernels import advance, legs, record

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]

DONE, GROW = 0, 1
"""Why ``fly_rounds`` returned: every lane finished, or the tracks must reach further."""


@compiled
def fly_rounds(
    level: IntArray,
    entered: FloatArray,
    blind_until: FloatArray,
    anchor: FloatArray,
    waypoint: FloatArray,
    memory: FloatArray,
    memory_count: IntArray,
    position: FloatArray,
    time: FloatArray,
    active: BoolArray,
    first: FloatArray,
    stop: FloatArray,
    gone: FloatArray,
    known: BoolArray,
    known_until: FloatArray,
    known_speed: FloatArray,
    visible: float,
    grown: float,
    seg_start: FloatArray,
    seg_velocity: FloatArray,
    filled: int,
    grid_dt: float,
    moving: bool,
    false_mask: BoolArray,
    appear: FloatArray,
    real: BoolArray,
    lifetimes: FloatArray,
    radii: FloatArray,
    memory_rule: int,
    memory_radius: float,
    blind_time: float,
    table: FloatArray,
    area: FloatArray,
    rule: int,
    from_anchor: bool,
    confine: bool,
    n_vehicles: int,
    speed: float,
    duration: float,
    cap: float,
    rng: np.random.Generator,
) -> tuple[int, float, int, FloatArray]:
    """Rounds until no lane is active (DONE) or a leg ends past the ``filled`` path segments
    (GROW). Returns why, the time the tracks must reach, the rounds flown and the memory (a
    grown copy once a lane remembers more targets than it has room for)."""
    last = radii.shape[0] - 1
    rounds = 0
    # One round's arrays, allocated once for every lane of the block and cut to the round's
    # lanes: allocated afresh each round, they cost page faults and zeroing as big as their use.
    total, m = first.shape
    lane_buf = np.empty(total, dtype=np.intp)
    run_buf = np.empty(total, dtype=np.intp)
    t_buf = np.empty(total)
    unit_buf = np.empty((total, 2))
    leg_buf = np.empty(total)
    left_buf = np.empty(total)
    horizon_buf = np.empty(total)
    exact_buf = np.empty(total, dtype=np.bool_)
    sensed_buf = np.empty((total, m), dtype=np.bool_)
    entry = np.empty(m)
    reached_buf = np.empty(total, dtype=np.bool_)
    contacts_buf = np.empty((total, m), dtype=np.bool_)
    where_buf = np.empty((total, m, 2))
    flags_buf = np.empty((total, 4), dtype=np.bool_)
    now_buf = np.empty(total)
    at_buf = np.empty((total, 2))
    while True:
        n = 0
        for lane in range(total):
            if active[lane]:
                lane_buf[n] = lane
                n += 1
        if n == 0:
            return DONE, 0.0, rounds, memory
        lanes = lane_buf[:n]
        runs = run_buf[:n]
        t = t_buf[:n]
        exact = exact_buf[:n]
        for i in range(n):
            runs[i] = lanes[i] // n_vehicles
            t[i] = time[lanes[i]]
            exact[i] = memory_rule == EXACT or level[lanes[i]] == last
        unit = unit_buf[:n]
        leg = leg_buf[:n]
        left = left_buf[:n]
        horizon = horizon_buf[:n]
        until = legs(
            waypoint,
            position,
            time,
            level,
            entered,
            blind_until,
            lifetimes,
            stop,
            lanes,
            runs,
            speed,
            unit,
            leg,
            left,
            horizon,
        )
        if moving and math.floor(until / grid_dt + NODE_EPS) >= filled:
            return GROW, until, rounds, memory
        sensed = eligible(
            known,
            known_until,
            known_speed,
            visible,
            memory,
            memory_count,
            lanes,
            runs,
            t,
            exact,
            seg_start,
            seg_velocity,
            grid_dt,
            moving,
            memory_radius,
            sensed_buf[:n],
        )
        visible = grown  # the next rounds see this call's paths
        reached = reached_buf[:n]
        contacts = contacts_buf[:n]
        where = where_buf[:n]
        advance(
            level,
            blind_until,
            memory,
            memory_count,
            position,
            time,
            waypoint,
            lanes,
            runs,
            unit,
            leg,
            left,
            horizon,
            sensed,
            radii,
            memory_rule,
            false_mask,
            appear,
            seg_start,
            seg_velocity,
            grid_dt,
            grown,
            moving,
            speed,
            entry,
            reached,
            contacts,
            where,
        )
        now = now_buf[:n]
        at = at_buf[:n]
        for i in range(n):
            now[i] = time[lanes[i]]
            at[i, 0] = position[lanes[i], 0]
            at[i, 1] = position[lanes[i], 1]
        new = contacts  # the step turns the contacts into the new confirmations in place
        flags = flags_buf[:n]
        step_lanes(
            level,
            entered,
            blind_until,
            anchor,
            memory,
            memory_count,
            lanes,
            now,
            at,
            reached,
            contacts,
            where,
            lifetimes,
            radii,
            memory_radius,
            memory_rule,
            blind_time,
            waypoint,
            table,
            area,
            rule,
            from_anchor,
            confine,
            rng,
            new,
            flags,
        )
        confirmed = flags[:, CONFIRMED]
        memory = remember_confirmed(memory, memory_count, lanes, new, where, confirmed)
        for i in range(n):
            if confirmed[i]:
                known_until[lanes[i]] = -np.inf
        rounds += 1
        record(
            first,
            stop,
            gone,
            active,
            confirmed,
            new,
            lanes,
            runs,
            time,
            real,
            n_vehicles,
            duration,
            cap,
        )
