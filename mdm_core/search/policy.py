"""The MDM search policy (section III), batched over vehicles. A live vehicle is a batch of one.

The policy is pure: it is handed the time, positions and sensor contacts, and the numpy Generator
to draw from; it keeps no clock and does no I/O. One ``step`` call applies, for each vehicle:

1. contacts of the active sensor that are not a target it confirmed itself (its memory):
   on a detection level -> next level, the point of detection becomes the anchor;
   on the confirmation level -> remember the targets, back to level 1;
2. the decaying index of levels >= 2 (C_I, D^k_I) below its bound -> back to level 1;
3. a new waypoint P_{q+1} = P_q + delta_k D(S_t) when the level changed or the waypoint was
   reached.

This is the reference implementation of the policy. The companion runs it (a batch of one);
the Monte-Carlo engine runs compiled twins of its hot parts, each tested bit for bit against
this code. A change here is made in its twin too, or those tests fail (docs/architecture.md,
"The search policy and its compiled twins", lists the pairs):

- ``step``: mdm_montecarlo/kernels/policy_step.py (tests/montecarlo/test_compiled_policy.py);
- ``_next_waypoints``, the start waypoints: mdm_montecarlo/kernels/policy_waypoints.py
  (test_compiled_policy.py);
- ``memory_distance2``: mdm_montecarlo/kernels/policy_memory.py (test_compiled_memory.py) and
  mdm_montecarlo/kernels/remembered.py (test_remembered.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mdm_core.search.distributions import directions, symmetric_stable
from mdm_core.search.levels import PolicyConfig
from mdm_core.search.planar import length

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]
_REDRAWS = 16
_STUCK = 1e-6
"""Metres: a waypoint this close to the vehicle would give a leg that takes no time."""
_BATCH = 64
"""Redraw candidates drawn per call once few lanes are left (see SearchPolicy._draw)."""


@dataclass
class PolicyState:
    """What each vehicle's policy remembers between steps (arrays over vehicles)."""

    level: IntArray
    """Current level, 0-based (level 1 of the paper is 0)."""
    waypoint: FloatArray
    """Current waypoint (n, 2)."""
    anchor: FloatArray
    """Point of the last detection (n, 2)."""
    entered: FloatArray
    """Time the current level was entered (n,)."""
    memory: FloatArray
    """Positions of targets this vehicle confirmed itself (n, K, 2); rows past memory_count unused."""
    memory_count: IntArray
    """How many memory rows are in use (n,)."""
    blind_until: FloatArray
    """Level 1 ignores detections before this time (n,); -inf: not blind (fallback_blind_time)."""

    @property
    def size(self) -> int:
        return len(self.level)

    def make_room(self, slots: int) -> None:
        """Give memory room for ``slots`` targets per vehicle (at least doubling it), the
        remembered ones kept."""
        room = self.memory.shape[1]
        if slots > room:
            grow = max(slots, 2 * room) - room
            self.memory = np.concatenate([self.memory, np.zeros((self.size, grow, 2))], axis=1)


@dataclass
class Observation:
    """What a batch of vehicles observed since their last step."""

    time: FloatArray
    """Vehicle time, seconds (n,)."""
    position: FloatArray
    """Positions (n, 2), metres (north, east)."""
    reached: BoolArray
    """True where the current waypoint was reached (n,)."""
    contacts: BoolArray
    """Targets the active sensor reports (n, m)."""
    contact_positions: FloatArray
    """Position estimates of those targets (n, m, 2); with ``detections``, of theirs too."""
    detections: BoolArray | None = None
    """(n, m) targets the detection sensor reports on the last level (policy.redetection);
    None: it is not read there."""


@dataclass
class StepOutcome:
    """What changed in a step (arrays over the stepped vehicles)."""

    detected: BoolArray
    confirmed: BoolArray
    """True where at least one new target was confirmed."""
    new_confirmations: BoolArray
    """(n, m): the contacts that were confirmed as new targets."""
    fell_back: BoolArray
    """True where the decaying index ended a level."""
    new_waypoint: BoolArray


class SearchPolicy:
    """MDM for n >= 2 levels; with one level, the single-sensor search (US, BS, LS)."""

    def __init__(self, config: PolicyConfig) -> None:
        self.config = config
        self._lifetimes = np.array(
            [np.inf if lv.index is None else lv.index.lifetime for lv in config.levels]
        )
        self._radii = np.array([lv.sensor_radius for lv in config.levels])
        self._area = np.array(config.area, dtype=float)
        self._fence = np.array(config.fence, dtype=float).reshape(-1, 3)
        self._bounds = np.concatenate([self._area, self._fence.ravel()])
        """The area's size, then each fence half-plane's three numbers: what the compiled
        draws read (mdm_montecarlo.kernels.policy_waypoints._inside)."""

    @property
    def n_levels(self) -> int:
        return len(self.config.levels)

    def sensor_radius(self, state: PolicyState) -> FloatArray:
        """Radius of the sensor each vehicle has switched on."""
        return np.asarray(self._radii[state.level])

    def uses_confirmation_sensor(self, state: PolicyState) -> BoolArray:
        """True where the active sensor is the confirmation sensor (the last level)."""
        return np.asarray(state.level == self.n_levels - 1)

    def deadline(self, state: PolicyState) -> FloatArray:
        """Time at which each vehicle's decaying index falls below its bound; on level 1 the end
        of a blind period after a fall-back, else inf. A step at that time clears it."""
        out = state.entered + self._lifetimes[state.level]
        blind = np.isfinite(state.blind_until) & (state.level == 0)
        return np.asarray(np.where(blind, state.blind_until, out))

    def ignores_detections(
        self, state: PolicyState, lanes: IntArray, position: FloatArray, time: FloatArray
    ) -> BoolArray:
        """(len(lanes),) lanes on a detection level whose detections are ignored whatever
        target caused them: blind after a fall-back, or (detection_memory 'disc') a remembered
        target within the active sensor's radius of the vehicle at ``position`` (k, 2)."""
        level = state.level[lanes]
        detecting = level < self.n_levels - 1
        out = detecting & (time < state.blind_until[lanes])
        if self.config.detection_memory == "disc":
            near = self.memory_distance2(state, lanes, position[:, None, :])[:, 0]
            out |= detecting & (near < self._radii[level] ** 2)
        return np.asarray(out)

    def checks_exactly(self, state: PolicyState, lanes: IntArray) -> BoolArray:
        """(len(lanes),) lanes whose contacts are matched to memory by the target's position:
        the confirmation level always, detection levels with detection_memory 'exact'."""
        if self.config.detection_memory == "exact":
            return np.ones(len(lanes), dtype=bool)
        return np.asarray(state.level[lanes] == self.n_levels - 1)

    def index_value(self, state: PolicyState, time: FloatArray) -> FloatArray:
        """C_I (or D^k_I) of each vehicle at the given time; NaN on level 1."""
        out = np.full(state.size, np.nan)
        for k, level in enumerate(self.config.levels):
            if level.index is None:
                continue
            on = state.level == k
            out[on] = level.index.value(time[on] - state.entered[on])
        return out

    def start(
        self, position: FloatArray, time: FloatArray, rng: np.random.Generator
    ) -> PolicyState:
        """Fresh state for vehicles at the given positions, with a first level-1 waypoint."""
        n = len(position)
        state = PolicyState(
            level=np.zeros(n, dtype=np.intp),
            waypoint=np.array(position, dtype=float),
            anchor=np.array(position, dtype=float),
            entered=np.array(time, dtype=float),
            memory=np.zeros((n, 4, 2)),
            memory_count=np.zeros(n, dtype=np.intp),
            blind_until=np.full(n, -np.inf),
        )
        everyone = np.arange(n)
        state.waypoint[:] = self._next_waypoints(state, everyone, state.waypoint, rng)
        return state

    def remember(self, state: PolicyState, lanes: IntArray, positions: FloatArray) -> None:
        """Add confirmed target positions (k, 2) to the memory of ``lanes`` (k,).

        A lane may appear several times; its positions are stored in the order given.
        """
        order = np.argsort(lanes, kind="stable")
        by_lane = lanes[order]
        rank = np.empty(len(lanes), dtype=np.intp)
        rank[order] = np.arange(len(lanes)) - np.searchsorted(by_lane, by_lane)
        slot = state.memory_count[lanes] + rank
        state.make_room(int(slot.max(initial=-1)) + 1)
        state.memory[lanes, slot] = positions
        np.add.at(state.memory_count, lanes, 1)

    def known(self, state: PolicyState, lanes: IntArray, positions: FloatArray) -> BoolArray:
        """(len(lanes), m): True where a position lies within memory_radius of a remembered target."""
        return np.asarray(
            self.memory_distance2(state, lanes, positions) <= self.config.memory_radius**2
        )

    def memory_distance2(
        self, state: PolicyState, lanes: IntArray, positions: FloatArray
    ) -> FloatArray:
        """(len(lanes), m) squared distance from each position to the nearest target the lane
        remembers confirming (inf for a lane that remembers none)."""
        out = np.full(positions.shape[:2], np.inf)
        counts = state.memory_count[lanes]
        rows = np.flatnonzero(counts > 0)
        if rows.size == 0:
            return out
        # Every (row, used slot) pair once, grouped by row: sum(counts) x m work in all.
        per_row = counts[rows]
        owner = np.repeat(rows, per_row)
        starts = np.cumsum(per_row) - per_row
        slot = np.arange(owner.size) - np.repeat(starts, per_row)
        remembered = state.memory[lanes[owner], slot]
        north = positions[owner, :, 0] - remembered[:, 0, None]
        east = positions[owner, :, 1] - remembered[:, 1, None]
        out[rows] = np.minimum.reduceat(north * north + east * east, starts, axis=0)
        return out

    def step(
        self,
        state: PolicyState,
        lanes: IntArray,
        obs: Observation,
        rng: np.random.Generator,
    ) -> StepOutcome:
        """Apply one observation to the vehicles ``lanes`` of ``state`` (in place)."""
        last = self.n_levels - 1
        level = state.level[lanes]
        new = obs.contacts.copy()
        seen = np.flatnonzero(new.any(axis=1))
        if seen.size:
            exact = seen[self.checks_exactly(state, lanes[seen])]
            new[exact] &= ~self.known(state, lanes[exact], obs.contact_positions[exact])
            ignored = self.ignores_detections(
                state, lanes[seen], obs.position[seen], obs.time[seen]
            )
            new[seen[ignored]] = False
        has = new.any(axis=1)

        detected = has & (level < last)
        confirmed = has & (level == last)
        new_confirmations = new & confirmed[:, None]
        rows, cols = np.nonzero(new_confirmations)
        if rows.size:
            # One memory row per newly confirmed target (several may be seen at once).
            self.remember(state, lanes[rows], obs.contact_positions[rows, cols])

        next_level = np.where(detected, level + 1, level)
        next_level = np.where(confirmed, 0, next_level)
        # Same sum as deadline(): a step at exactly deadline() must fall back (no rounding gap).
        deadline = state.entered[lanes] + self._lifetimes[level]
        decides = obs.reached | (obs.time >= deadline)
        again, again_at = self.redetections(state, lanes, obs, ~has & decides)
        renewed = again if self.config.redetection == "renew" else np.zeros_like(again)
        expired = (next_level == level) & (level > 0) & (obs.time >= deadline) & ~renewed
        next_level = np.where(expired, 0, next_level)

        changed = next_level != level
        blind = state.blind_until[lanes]
        blind[obs.time >= blind] = -np.inf
        if self.config.fallback_blind_time > 0:
            blind[expired] = obs.time[expired] + self.config.fallback_blind_time
        state.blind_until[lanes] = blind
        state.level[lanes] = next_level
        state.entered[lanes] = np.where(changed | renewed, obs.time, state.entered[lanes])
        anchor = state.anchor[lanes]
        if self.config.anchor_at == "target":
            first = np.argmax(new, axis=1)  # the first detected target of each lane
            anchor[detected] = obs.contact_positions[detected, first[detected]]
        else:
            anchor[detected] = obs.position[detected]
        anchor[again] = again_at[again]
        state.anchor[lanes] = anchor

        redraw = changed | obs.reached
        chosen = lanes[redraw]
        if chosen.size:
            state.waypoint[chosen] = self._next_waypoints(state, chosen, obs.position[redraw], rng)
        return StepOutcome(detected, confirmed, new_confirmations, expired, redraw)

    def redetections(
        self, state: PolicyState, lanes: IntArray, obs: Observation, deciding: BoolArray
    ) -> tuple[BoolArray, FloatArray]:
        """policy.redetection: which ``deciding`` lanes on the last level read a detection
        there (checked against memory as detection_memory says), and where it anchors them
        (the vehicle, or with anchor_at 'target' the first such target). Nothing where the
        policy ignores the detection sensor on the last level."""
        n = len(lanes)
        anchors = np.zeros((n, 2))
        if self.config.redetection == "ignore" or obs.detections is None or self.n_levels < 2:
            return np.zeros(n, dtype=bool), anchors
        last = self.n_levels - 1
        rows = np.flatnonzero(deciding & (state.level[lanes] == last))
        seen = obs.detections[rows].copy()
        where = obs.contact_positions[rows]
        memory = self.config.detection_memory
        if memory == "exact":
            seen &= ~self.known(state, lanes[rows], where)
        elif memory == "disc":
            near = self.memory_distance2(state, lanes[rows], obs.position[rows, None, :])[:, 0]
            seen[near < self._radii[last - 1] ** 2] = False
        found = seen.any(axis=1)
        again = np.zeros(n, dtype=bool)
        again[rows[found]] = True
        if self.config.anchor_at == "target":
            first = np.argmax(seen, axis=1)
            anchors[rows[found]] = where[found, first[found]]
        else:
            anchors[rows[found]] = obs.position[rows[found]]
        return again, anchors

    def step_changes(
        self,
        state: PolicyState,
        lane: int,
        time: float,
        position: tuple[float, float],
        reached: bool,
        contacts: FloatArray,
    ) -> bool:
        """Whether :meth:`step` of the one vehicle ``lane`` (every contact in ``contacts`` (m, 2)
        seen) would change its state or report anything. On floats, with the comparisons of
        ``step``: a live vehicle near a target it confirmed reads it every telemetry tick, and
        a step that only finds it known is most of a sped-up companion's CPU there."""
        if reached:
            return True
        level = int(state.level[lane])
        blind = state.blind_until[lane]
        if time >= blind and blind != -np.inf:  # the step ends the blind period
            return True
        if level > 0 and time >= state.entered[lane] + self._lifetimes[level]:  # falls back
            return True
        if len(contacts) == 0:
            return False
        if level < self.n_levels - 1:  # a detection level: ignored, or a detection
            if time < blind:
                return False
            if self.config.detection_memory == "disc":
                radius = float(self._radii[level])
                if self._nearest2(state, lane, position) < radius * radius:
                    return False
            if self.config.detection_memory != "exact":
                return True
        known = self.config.memory_radius**2  # a NaN distance is not known, as in step
        return not all(self._nearest2(state, lane, (c[0], c[1])) <= known for c in contacts)

    def _nearest2(self, state: PolicyState, lane: int, point: tuple[float, float]) -> float:
        """:meth:`memory_distance2` of one point of one lane, on floats (a NaN wins, as in
        ``np.minimum``)."""
        best = np.inf
        for north, east in state.memory[lane, : state.memory_count[lane]]:
            dn, de = point[0] - north, point[1] - east
            d = dn * dn + de * de
            if not (math.isnan(best) or d >= best):
                best = d
        return float(best)

    def _next_waypoints(
        self, state: PolicyState, lanes: IntArray, position: FloatArray, rng: np.random.Generator
    ) -> FloatArray:
        out = np.empty((len(lanes), 2))
        level = state.level[lanes]
        for k in range(self.n_levels):
            rows = np.flatnonzero(level == k)
            if rows.size == 0:
                continue
            origin = position[rows]
            if k > 0 and self.config.waypoint_origin == "anchor":
                origin = state.anchor[lanes[rows]]
            out[rows] = self._draw(k, origin, state.anchor[lanes[rows]], position[rows], rng)
        return out

    def _draw(
        self,
        k: int,
        origin: FloatArray,
        anchor: FloatArray,
        position: FloatArray,
        rng: np.random.Generator,
    ) -> FloatArray:
        """P_q + delta_k D(S_t) from each origin; with the 'redraw' rule, the first of up to
        1 + _REDRAWS candidates that lies in the area and inside the fence's half-planes (the
        last one mirrored into the area if none does). With 'clip', a candidate clipped onto the vehicle's own ``position`` (a
        vehicle at a wall or corner stepping outwards) is mirrored instead: a leg of length 0
        takes no time and the mission would never advance."""
        points = self._candidates(k, origin, anchor, rng)
        if self.config.out_of_area != "redraw":
            folded = _fold_into_area(points, self._area, self.config.out_of_area)
            stuck = np.flatnonzero(length(folded - position) <= _STUCK)
            if stuck.size:
                folded[stuck] = _fold_into_area(points[stuck], self._area, "reflect")
            return folded
        pending = np.flatnonzero(~self._inside(points))
        left = _REDRAWS
        while pending.size:
            # Few lanes left: draw several of their candidates in one call (the same sequence of
            # independent candidates a draw-check-redraw loop would see, fewer numpy calls).
            per_lane = min(left, max(1, _BATCH // len(pending)))
            lanes = np.repeat(pending, per_lane)
            candidate = self._candidates(k, origin[lanes], anchor[lanes], rng)
            candidate = candidate.reshape(len(pending), per_lane, 2)
            left -= per_lane
            inside = self._inside(candidate)
            if left == 0:
                inside[:, -1] = True
                candidate[:, -1] = _fold_into_area(candidate[:, -1], self._area, "reflect")
            found = inside.any(axis=1)
            first = inside.argmax(axis=1)
            points[pending[found]] = candidate[found, first[found]]
            pending = pending[~found]
        return points

    def _inside(self, points: FloatArray) -> BoolArray:
        inside = ((points >= 0.0) & (points <= self._area)).all(axis=-1)
        for n_north, n_east, offset in self._fence:
            # the compiled test's arithmetic, operation for operation (no fused multiply-add)
            inside &= points[..., 0] * n_north + points[..., 1] * n_east >= offset
        return np.asarray(inside)

    def _candidates(
        self, k: int, origin: FloatArray, anchor: FloatArray, rng: np.random.Generator
    ) -> FloatArray:
        """One candidate waypoint per origin (n, 2), confined to the detection disc if set."""
        cfg = self.config.levels[k]
        n = len(origin)
        scale: FloatArray | float = cfg.step
        if cfg.step_law == "levy":
            # Drawn before the direction (the order of the random stream).
            size = np.abs(symmetric_stable(rng, cfg.step_index, 1.0, (n,)))
            scale = (cfg.step * np.minimum(size, cfg.step_cap))[:, None]
        step = directions(cfg.sampler, rng, n)
        step *= scale
        candidate = origin + step
        if k > 0 and self.config.confine_to_detection:
            candidate = _fold_into_disc(candidate, anchor, self._radii[k - 1])
        return candidate


def _fold_into_area(points: FloatArray, size: FloatArray, rule: str) -> FloatArray:
    if rule == "clip":
        return np.clip(points, 0.0, size)
    period = 2.0 * size
    folded = np.mod(points, period)
    return np.where(folded > size, period - folded, folded)


def _fold_into_disc(points: FloatArray, centre: FloatArray, radius: float) -> FloatArray:
    """Mirror points that lie outside the disc back across its rim (radially)."""
    offset = points - centre
    dist = length(offset)
    out = np.array(points)
    far = np.flatnonzero(dist > radius)
    if far.size:
        # Triangle wave of the distance: mirror at the rim, again at the centre, and so on.
        folded = np.mod(dist[far], 2 * radius)
        folded = np.where(folded > radius, 2 * radius - folded, folded)
        out[far] = centre[far] + offset[far] * (folded / dist[far])[:, None]
    return out
