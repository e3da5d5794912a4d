"""The batch engine's rounds, compiled (numba) into one loop: a block runs in a few calls.

A round moves every active lane to its next event: ``legs``, the remembered targets
(``remembered.eligible``), ``advance``, the policy step and its memory update
(``policy_step``), ``record``. Called from Python, each round cost two dozen numpy calls
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
from mdm_montecarlo.kernels.policy_step import (
    CONFIRMED,
    EXACT,
    LaneState,
    PolicyRules,
    Seen,
    remember_confirmed,
    step_lanes,
)
from mdm_montecarlo.kernels.remembered import Remembered, eligible
from mdm_montecarlo.kernels.round_kernels import advance, legs, record
from mdm_montecarlo.kernels.round_state import Block, Events, Flight, Legs, Paths, Stepped

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]

DONE, GROW = 0, 1
"""Why ``fly_rounds`` returned: every lane finished, or the tracks must reach further."""


@compiled
def fly_rounds(
    state: LaneState,
    flight: Flight,
    remembered: Remembered,
    paths: Paths,
    block: Block,
    rules: PolicyRules,
    rng: np.random.Generator,
) -> tuple[int, float, int, FloatArray]:
    """Rounds until no lane is active (DONE) or a leg ends past the ``paths.filled`` path
    segments (GROW). Returns why, the time the tracks must reach, the rounds flown and the
    memory (a grown copy once a lane remembers more targets than it has room for)."""
    radii = rules.radii
    last = radii.shape[0] - 1
    n_vehicles = block.n_vehicles
    rounds = 0
    visible = paths.visible
    # One round's arrays, allocated once for every lane of the block and cut to the round's
    # lanes: allocated afresh each round, they cost page faults and zeroing as big as their use.
    total, m = flight.first.shape
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
    detections_buf = np.zeros((total, m), dtype=np.bool_)
    flags_buf = np.empty((total, 4), dtype=np.bool_)
    now_buf = np.empty(total)
    at_buf = np.empty((total, 2))
    while True:
        n = 0
        for lane in range(total):
            if flight.active[lane]:
                lane_buf[n] = lane
                n += 1
        if n == 0:
            return DONE, 0.0, rounds, state.memory
        lanes = lane_buf[:n]
        runs = run_buf[:n]
        t = t_buf[:n]
        exact = exact_buf[:n]
        for i in range(n):
            runs[i] = lanes[i] // n_vehicles
            t[i] = flight.time[lanes[i]]
            exact[i] = rules.memory_rule == EXACT or state.level[lanes[i]] == last
        stepped = Stepped(lanes, runs, t, exact)
        leg = Legs(unit_buf[:n], leg_buf[:n], left_buf[:n], horizon_buf[:n])
        until = legs(state, flight, rules.lifetimes, block.speed, stepped, leg)
        if paths.moving and math.floor(until / paths.grid_dt + NODE_EPS) >= paths.filled:
            return GROW, until, rounds, state.memory
        seen_paths = Paths(
            paths.seg_start,
            paths.seg_velocity,
            paths.filled,
            paths.grid_dt,
            paths.moving,
            visible,
            paths.grown,
        )
        sensed = eligible(
            remembered, state, stepped, seen_paths, rules.memory_radius, sensed_buf[:n]
        )
        visible = paths.grown  # the next rounds see this call's paths
        events = Events(
            sensed, entry, reached_buf[:n], contacts_buf[:n], where_buf[:n], detections_buf[:n]
        )
        advance(state, flight, stepped, leg, paths, block, rules, events)
        now = now_buf[:n]
        at = at_buf[:n]
        for i in range(n):
            now[i] = flight.time[lanes[i]]
            at[i, 0] = flight.position[lanes[i], 0]
            at[i, 1] = flight.position[lanes[i], 1]
        # The step turns the contacts into the new confirmations in place.
        new = events.contacts
        flags = flags_buf[:n]
        seen = Seen(now, at, events.reached, events.contacts, events.where, events.detections)
        step_lanes(state, lanes, seen, rules, rng, new, flags)
        confirmed = flags[:, CONFIRMED]
        memory = remember_confirmed(
            state.memory, state.memory_count, lanes, new, events.where, confirmed
        )
        state = LaneState(
            state.level,
            state.entered,
            state.blind_until,
            state.anchor,
            state.waypoint,
            memory,
            state.memory_count,
        )
        for i in range(n):
            if confirmed[i]:
                remembered.until[lanes[i]] = -np.inf
        rounds += 1
        record(flight, stepped, confirmed, new, block)
