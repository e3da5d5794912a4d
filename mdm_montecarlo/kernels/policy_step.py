"""The batch engine's policy step, compiled (numba), bit-identical to ``SearchPolicy.step``.

Twin of mdm_core/search/policy.py's ``SearchPolicy.step`` (its waypoint draws, and
``CompiledPolicy.explore``, the twin of mdm_core/search/swarm_iteration.py's ``explore``, are
policy_waypoints.py's): a change to one is made in the other.

``SearchPolicy.step`` is some forty numpy calls on (lanes,) and (lanes, targets) arrays per
event: the memory checks of the contacts, the level changes, the decaying index, the blind
period, the anchor. Here one loop per lane makes the same comparisons and the same sums in the
same order; the waypoints are then drawn by the compiled draws of ``policy_waypoints`` and the
confirmed targets remembered in one more loop, as ``step`` and ``remember`` do. The companion
keeps the numpy policy (tests/montecarlo/test_compiled_policy.py compares the two on random
states).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled
from mdm_core.search.levels import PolicyConfig
from mdm_core.search.policy import Observation, PolicyState, StepOutcome
from mdm_montecarlo.kernels.policy_waypoints import CompiledWaypoints, Draws, next_waypoints

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]

DISC, EXACT, NONE = 0, 1, 2
_MEMORY = {"disc": DISC, "exact": EXACT, "none": NONE}
IGNORE, RECENTRE, RENEW = 0, 1, 2
_REDETECTION = {"ignore": IGNORE, "recentre": RECENTRE, "renew": RENEW}
# Columns of the flags the kernel returns per lane.
DETECTED, CONFIRMED, EXPIRED, REDRAW = range(4)


class PolicyRules(NamedTuple):
    """A configuration's policy as the kernels read it, built once per policy
    (``CompiledPolicy.rules``)."""

    lifetimes: FloatArray
    """Seconds each level lasts before its decaying index ends it (inf on level 1)."""
    radii: FloatArray
    """Sensor radius of each level, metres."""
    memory_radius: float
    memory_rule: int
    """detection_memory: DISC, EXACT or NONE."""
    blind_time: float
    """fallback_blind_time, seconds."""
    draws: Draws
    on_target: bool
    """anchor_at == "target": a detection anchors on the detected target's position."""
    redetect: int
    """policy.redetection: IGNORE, RECENTRE or RENEW."""


class LaneState(NamedTuple):
    """PolicyState's arrays as the kernels read them. A kernel that grows the memory (a new,
    larger array: ``remember_confirmed``) goes on with a new LaneState holding it."""

    level: IntArray
    entered: FloatArray
    blind_until: FloatArray
    anchor: FloatArray
    waypoint: FloatArray
    memory: FloatArray
    memory_count: IntArray


def lane_state(state: PolicyState) -> LaneState:
    """The kernels' view of ``state`` (the same arrays)."""
    return LaneState(
        state.level,
        state.entered,
        state.blind_until,
        state.anchor,
        state.waypoint,
        state.memory,
        state.memory_count,
    )


class Seen(NamedTuple):
    """What the stepped lanes report (Observation's arrays, one row per stepped lane)."""

    time: FloatArray
    position: FloatArray
    reached: BoolArray
    contacts: BoolArray
    contact_positions: FloatArray
    detections: BoolArray
    """(n, m) the detection sensor on the last level (read only with a redetection rule)."""


@compiled
def nearest2(memory: FloatArray, count: int, lane: int, x: float, y: float) -> float:
    """Squared distance from (x, y) to the nearest remembered target (memory_distance2)."""
    best = np.inf
    for slot in range(count):
        north = x - memory[lane, slot, 0]
        east = y - memory[lane, slot, 1]
        d2 = north * north + east * east
        if math.isnan(d2):
            return float(d2)
        best = min(best, d2)
    return float(best)


@compiled
def remember_confirmed(
    memory: FloatArray,
    memory_count: IntArray,
    lanes: IntArray,
    new_confirmations: BoolArray,
    contact_positions: FloatArray,
    confirmed: BoolArray,
) -> FloatArray:
    """SearchPolicy.remember of the new confirmations (n, m) of the ``confirmed`` rows of
    distinct ``lanes``, a lane's in target order, with their contact positions (n, m, 2).
    Returns the memory: ``memory`` itself, or a copy grown as PolicyState.make_room grows it."""
    n, m = new_confirmations.shape
    needed = 0
    for i in range(n):
        if confirmed[i]:
            count = memory_count[lanes[i]]
            for j in range(m):
                count += new_confirmations[i, j]
            needed = max(needed, count)
    room = memory.shape[1]
    if needed > room:
        grown = np.zeros((memory.shape[0], max(needed, 2 * room), 2))
        grown[:, :room] = memory
        memory = grown
    for i in range(n):
        if not confirmed[i]:
            continue
        lane = lanes[i]
        for j in range(m):
            if new_confirmations[i, j]:
                slot = memory_count[lane]
                memory[lane, slot, 0] = contact_positions[i, j, 0]
                memory[lane, slot, 1] = contact_positions[i, j, 1]
                memory_count[lane] = slot + 1
    return memory


@compiled
def redetected(state: LaneState, lane: int, i: int, observed: Seen, rules: PolicyRules) -> int:
    """SearchPolicy.redetections of one lane, row ``i`` of ``observed``: the first target its
    detection sensor reports on the last level that memory does not rule out, or -1."""
    memory, count = state.memory, state.memory_count[lane]
    position, detections, where = observed.position, observed.detections, observed.contact_positions
    radius = rules.radii[rules.radii.shape[0] - 2]
    here = position[i]
    if rules.memory_rule == DISC and nearest2(memory, count, lane, here[0], here[1]) < radius**2:
        return -1
    known2 = rules.memory_radius**2
    for j in range(detections.shape[1]):
        if not detections[i, j]:
            continue
        if rules.memory_rule != EXACT:
            return j
        if not nearest2(memory, count, lane, where[i, j, 0], where[i, j, 1]) <= known2:
            return j
    return -1


@compiled
def step_lanes(
    state: LaneState,
    lanes: IntArray,
    observed: Seen,
    rules: PolicyRules,
    rng: np.random.Generator,
    new: BoolArray,
    flags: BoolArray,
) -> None:
    """SearchPolicy.step without the memory update, lanes distinct.

    Updates level, entered, blind_until, anchor and waypoint in place; writes the new
    confirmations ``new`` (n, m) and the flags ``flags`` (n, 4) DETECTED, CONFIRMED, EXPIRED,
    REDRAW. ``new`` may be ``contacts`` itself: a lane's row of contacts is read only before
    its row of ``new`` is written."""
    level, entered, blind_until, anchor, waypoint, memory, memory_count = state
    time, position, reached, contacts, contact_positions = observed[:5]
    lifetimes, radii, memory_radius, detection_memory, blind_time, draws, on_target, redetect = (
        rules
    )
    n, m = contacts.shape
    last = radii.shape[0] - 1
    known2 = memory_radius**2
    for i in range(n):
        lane = lanes[i]
        lvl = level[lane]
        seen = False
        for j in range(m):
            new[i, j] = contacts[i, j]
            seen = seen or new[i, j]
        if seen:
            count = memory_count[lane]
            if detection_memory == EXACT or lvl == last:
                for j in range(m):
                    if new[i, j]:
                        d2 = nearest2(
                            memory,
                            count,
                            lane,
                            contact_positions[i, j, 0],
                            contact_positions[i, j, 1],
                        )
                        if d2 <= known2:
                            new[i, j] = False
            detecting = lvl < last
            ignored = detecting and time[i] < blind_until[lane]
            if detection_memory == DISC:
                near = nearest2(memory, count, lane, position[i, 0], position[i, 1])
                ignored = ignored or (detecting and near < radii[lvl] ** 2)
            if ignored:
                for j in range(m):
                    new[i, j] = False
        has = False
        for j in range(m):
            has = has or new[i, j]
        detected = has and lvl < last
        confirmed = has and lvl == last
        next_level = lvl + 1 if detected else lvl
        if confirmed:
            next_level = 0
        deadline = entered[lane] + lifetimes[lvl]
        again = -1  # the target the detection sensor reports again on the last level
        if redetect != IGNORE and lvl == last and not has and (reached[i] or time[i] >= deadline):
            again = redetected(state, lane, i, observed, rules)
        renewed = again >= 0 and redetect == RENEW
        expired = next_level == lvl and lvl > 0 and time[i] >= deadline and not renewed
        if expired:
            next_level = 0
        changed = next_level != lvl
        blind = blind_until[lane]
        if time[i] >= blind:
            blind = -np.inf
        if blind_time > 0 and expired:
            blind = time[i] + blind_time
        blind_until[lane] = blind
        level[lane] = next_level
        if changed or renewed:
            entered[lane] = time[i]
        if detected and on_target:
            first = 0
            while not new[i, first]:
                first += 1
            anchor[lane, 0] = contact_positions[i, first, 0]
            anchor[lane, 1] = contact_positions[i, first, 1]
        elif detected:
            anchor[lane, 0] = position[i, 0]
            anchor[lane, 1] = position[i, 1]
        if again >= 0:
            spot = contact_positions[i, again] if on_target else position[i]
            anchor[lane, 0] = spot[0]
            anchor[lane, 1] = spot[1]
        flags[i, DETECTED] = detected
        flags[i, CONFIRMED] = confirmed
        flags[i, EXPIRED] = expired
        flags[i, REDRAW] = changed or reached[i]
        if not confirmed:
            for j in range(m):
                new[i, j] = False
    # The redrawn lanes' levels, anchors and positions, gathered in one loop (numba's masked
    # and fancy indexing of the same took twice as long).
    count = 0
    for i in range(n):
        count += flags[i, REDRAW]
    chosen = np.empty(count, dtype=np.intp)
    chosen_level = np.empty(count, dtype=level.dtype)
    chosen_anchor = np.empty((count, 2))
    chosen_position = np.empty((count, 2))
    c = 0
    for i in range(n):
        if flags[i, REDRAW]:
            lane = lanes[i]
            chosen[c] = lane
            chosen_level[c] = level[lane]
            chosen_anchor[c, 0] = anchor[lane, 0]
            chosen_anchor[c, 1] = anchor[lane, 1]
            chosen_position[c, 0] = position[i, 0]
            chosen_position[c, 1] = position[i, 1]
            c += 1
    if count:
        points = next_waypoints(draws, chosen_level, chosen_anchor, chosen_position, rng)
        for c in range(count):
            waypoint[chosen[c], 0] = points[c, 0]
            waypoint[chosen[c], 1] = points[c, 1]


class CompiledPolicy(CompiledWaypoints):
    """The engine's policy: step, memory check and waypoint draws compiled (numba)."""

    def __init__(self, config: PolicyConfig) -> None:
        super().__init__(config)
        self._rules = (
            None
            if self.draws is None
            else PolicyRules(
                self._lifetimes,
                self._radii,
                float(config.memory_radius),
                _MEMORY[config.detection_memory],
                float(config.fallback_blind_time),
                self.draws,
                config.anchor_at == "target",
                _REDETECTION[config.redetection],
            )
        )

    @property
    def rules(self) -> PolicyRules | None:
        """The policy as the kernels read it; None where only numpy's draws can draw."""
        return self._rules

    def step(
        self,
        state: PolicyState,
        lanes: IntArray,
        obs: Observation,
        rng: np.random.Generator,
    ) -> StepOutcome:
        """SearchPolicy.step for distinct ``lanes`` (as the engine steps them)."""
        if self._rules is None:
            return super().step(state, lanes, obs, rng)
        n, m = obs.contacts.shape
        new_confirmations = np.empty((n, m), dtype=bool)
        flags = np.empty((n, 4), dtype=bool)
        detections = np.zeros((n, m), dtype=bool) if obs.detections is None else obs.detections
        observed = Seen(
            obs.time, obs.position, obs.reached, obs.contacts, obs.contact_positions, detections
        )
        step_lanes(lane_state(state), lanes, observed, self._rules, rng, new_confirmations, flags)
        confirmed = flags[:, CONFIRMED]
        state.memory = remember_confirmed(
            state.memory,
            state.memory_count,
            lanes,
            new_confirmations,
            obs.contact_positions,
            confirmed,
        )
        return StepOutcome(
            flags[:, DETECTED], confirmed, new_confirmations, flags[:, EXPIRED], flags[:, REDRAW]
        )
