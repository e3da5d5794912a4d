"""The batch engine's waypoint draws, compiled (numba), bit-identical to the numpy policy's.

``SearchPolicy._next_waypoints`` draws, level by level, a step length (Levy step law), a
direction, folds into the detection disc and into the area, and redraws candidates that land
outside: a dozen numpy calls on small arrays per level and per redraw round, about a third of
the engine's time (docs/model.md, "Speed of reproduce"). Here the same draws come from the same
``numpy.random.Generator`` (numba draws from it in place, the same numbers as numpy), in the
same order as the vectorised code draws them (all of one array before the next), and every
value goes through the numpy version's operations in its order. The results are bit for bit the
numpy policy's (tests/montecarlo/test_compiled_waypoints.py); so are the streams after the call.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled
from mdm_core.search.distributions import Brownian, Levy, Uniform
from mdm_core.search.levels import PolicyConfig
from mdm_core.search.policy import _BATCH, _REDRAWS, _STUCK, PolicyState
from mdm_core.search.swarm_iteration import explore
from mdm_montecarlo.kernels.compiled_memory import CompiledMemoryPolicy

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

LEVY, BROWNIAN, UNIFORM = 0, 1, 2
REFLECT, CLIP, REDRAW = 0, 1, 2
RULES = {"reflect": REFLECT, "clip": CLIP, "redraw": REDRAW}
# Columns of the per-level table handed to the kernel.
(
    _SAMPLER,
    _P1,
    _P2,
    _STEP,
    _LEVY_STEP,
    _STEP_INDEX,
    _STEP_CAP,
    _DISC,
) = range(8)


@compiled
def _stable(rng: np.random.Generator, index: float, scale: float, n: int) -> FloatArray:
    """symmetric_stable(rng, index, scale, (n,)): n uniforms, then n exponentials."""
    v = np.empty(n)
    w = np.empty(n)
    for i in range(n):
        v[i] = rng.uniform(-np.pi / 2, np.pi / 2)
    for i in range(n):
        w[i] = rng.exponential(1.0)
    factor = scale ** (1.0 / index)
    out = np.empty(n)
    for i in range(n):
        if abs(index - 1.0) < 1e-12:
            x = math.tan(v[i])
        else:
            x = (
                math.sin(index * v[i])
                / math.cos(v[i]) ** (1.0 / index)
                * (math.cos(v[i] - index * v[i]) / w[i]) ** ((1.0 - index) / index)
            )
        out[i] = x * factor
    return out


@compiled
def _mod(a: float, b: float) -> float:
    """numpy's float remainder (the sign of the divisor), b > 0."""
    out = float(np.fmod(a, b))
    if out < 0.0:
        out += b
    elif out == 0.0:
        out = 0.0  # not -0.0
    return out


@compiled
def clip(value: float, size: float) -> float:
    """np.clip(value, 0, size) of one coordinate."""
    return min(max(value, 0.0), size)


@compiled
def _fold(value: float, size: float, rule: int) -> float:
    """_fold_into_area for one coordinate: clip onto [0, size] or mirror into it."""
    if rule == CLIP:
        return clip(value, size)
    period = 2.0 * size
    folded = _mod(value, period)
    return period - folded if folded > size else folded


@compiled
def _candidates(
    table: FloatArray,
    k: int,
    origin: FloatArray,
    anchor: FloatArray,
    confine: bool,
    rng: np.random.Generator,
) -> FloatArray:
    """SearchPolicy._candidates: one candidate per origin, in the numpy draw order."""
    n = origin.shape[0]
    scale = np.full(n, table[k, _STEP])
    if table[k, _LEVY_STEP] > 0:
        size = _stable(rng, table[k, _STEP_INDEX], 1.0, n)
        for i in range(n):
            scale[i] = table[k, _STEP] * min(abs(size[i]), table[k, _STEP_CAP])
    kind = int(table[k, _SAMPLER])
    if kind == LEVY:
        raw = _stable(rng, table[k, _P1], table[k, _P2], 2 * n)
    else:
        raw = np.empty(2 * n)
        for i in range(2 * n):
            if kind == BROWNIAN:
                raw[i] = rng.normal(0.0, table[k, _P1])
            else:
                raw[i] = rng.uniform(table[k, _P1], table[k, _P2])
    out = np.empty((n, 2))
    radius = table[k, _DISC]
    for i in range(n):
        x = raw[2 * i]
        y = raw[2 * i + 1]
        norm = math.sqrt(x * x + y * y)
        if norm == 0.0:
            x, y, norm = 1.0, 0.0, 1.0
        px = origin[i, 0] + x / norm * scale[i]
        py = origin[i, 1] + y / norm * scale[i]
        if k > 0 and confine:
            ox = px - anchor[i, 0]
            oy = py - anchor[i, 1]
            dist = math.sqrt(ox * ox + oy * oy)
            if dist > radius:
                folded = _mod(dist, 2 * radius)
                if folded > radius:
                    folded = 2 * radius - folded
                px = anchor[i, 0] + ox * (folded / dist)
                py = anchor[i, 1] + oy * (folded / dist)
        out[i, 0] = px
        out[i, 1] = py
    return out


@compiled
def _inside(x: float, y: float, area: FloatArray) -> bool:
    """In the area (area[0], area[1]) and on the inner side of each fence half-plane that
    follows it (n_north, n_east, offset: SearchPolicy._inside, the same arithmetic)."""
    inside = x >= 0.0 and x <= area[0] and y >= 0.0 and y <= area[1]
    j = 2
    while inside and j < area.shape[0]:
        inside = x * area[j] + y * area[j + 1] >= area[j + 2]
        j += 3
    return inside


@compiled
def _draw(
    table: FloatArray,
    k: int,
    origin: FloatArray,
    anchor: FloatArray,
    position: FloatArray,
    area: FloatArray,
    rule: int,
    confine: bool,
    rng: np.random.Generator,
) -> FloatArray:
    """SearchPolicy._draw for the lanes of one level."""
    points = _candidates(table, k, origin, anchor, confine, rng)
    n = points.shape[0]
    if rule != REDRAW:
        for i in range(n):
            fx = _fold(points[i, 0], area[0], rule)
            fy = _fold(points[i, 1], area[1], rule)
            dx = fx - position[i, 0]
            dy = fy - position[i, 1]
            if math.sqrt(dx * dx + dy * dy) <= _STUCK:
                fx = _fold(points[i, 0], area[0], REFLECT)
                fy = _fold(points[i, 1], area[1], REFLECT)
            points[i, 0] = fx
            points[i, 1] = fy
        return points
    pending = np.empty(n, dtype=np.intp)
    count = 0
    for i in range(n):
        if not _inside(points[i, 0], points[i, 1], area):
            pending[count] = i
            count += 1
    left = _REDRAWS
    while count:
        per_lane = min(left, max(1, _BATCH // count))
        rows = np.empty(count * per_lane, dtype=np.intp)
        for p in range(count):
            rows[p * per_lane : (p + 1) * per_lane] = pending[p]
        candidate = _candidates(table, k, origin[rows], anchor[rows], confine, rng)
        left -= per_lane
        still = 0
        for p in range(count):
            lane = pending[p]
            found = False
            for c in range(per_lane):
                row = p * per_lane + c
                x = candidate[row, 0]
                y = candidate[row, 1]
                last = left == 0 and c == per_lane - 1
                if last:
                    x = _fold(x, area[0], REFLECT)
                    y = _fold(y, area[1], REFLECT)
                if last or _inside(x, y, area):
                    points[lane, 0] = x
                    points[lane, 1] = y
                    found = True
                    break
            if not found:
                pending[still] = lane
                still += 1
        count = still
    return points


@compiled
def next_waypoints(
    table: FloatArray,
    level: IntArray,
    anchor: FloatArray,
    position: FloatArray,
    area: FloatArray,
    rule: int,
    from_anchor: bool,
    confine: bool,
    rng: np.random.Generator,
) -> FloatArray:
    """SearchPolicy._next_waypoints for lanes at ``level`` (n,) with anchors and positions (n, 2)."""
    n = level.shape[0]
    out = np.empty((n, 2))
    for k in range(table.shape[0]):
        rows = np.flatnonzero(level == k)
        if rows.size == 0:
            continue
        origin = anchor[rows] if k > 0 and from_anchor else position[rows]
        points = _draw(table, k, origin, anchor[rows], position[rows], area, rule, confine, rng)
        for p in range(rows.size):
            out[rows[p], 0] = points[p, 0]
            out[rows[p], 1] = points[p, 1]
    return out


def level_table(config: PolicyConfig) -> FloatArray | None:
    """The per-level parameters as the kernel reads them; None for a sampler it does not know
    or a stable index out of range (the numpy path then draws, or raises its clear error)."""
    rows = []
    for k, level in enumerate(config.levels):
        sampler = level.sampler
        if level.step_law == "levy" and not 0 < level.step_index <= 2:
            return None
        if isinstance(sampler, Levy):
            if not 0 < sampler.index <= 2:
                return None
            kind, p1, p2 = LEVY, sampler.index, sampler.scale
        elif isinstance(sampler, Brownian):
            kind, p1, p2 = BROWNIAN, sampler.sigma, 0.0
        elif isinstance(sampler, Uniform):
            kind, p1, p2 = UNIFORM, sampler.low, sampler.high
        else:
            return None
        disc = config.levels[k - 1].sensor_radius if k > 0 else 0.0
        levy_step = 1.0 if level.step_law == "levy" else 0.0
        rows.append([kind, p1, p2, level.step, levy_step, level.step_index, level.step_cap, disc])
    return np.array(rows, dtype=np.float64)


class CompiledWaypoints(CompiledMemoryPolicy):
    """SearchPolicy with its memory check and waypoint draws compiled, the rest numpy's."""

    def __init__(self, config: PolicyConfig) -> None:
        super().__init__(config)
        self._table = level_table(config)

    def _next_waypoints(
        self, state: PolicyState, lanes: IntArray, position: FloatArray, rng: np.random.Generator
    ) -> FloatArray:
        if self._table is None:
            return super()._next_waypoints(state, lanes, position, rng)
        return self._compiled_draw(
            self._table, state.level[lanes], state.anchor[lanes], position, rng
        )

    def explore(self, position: FloatArray, rng: np.random.Generator) -> FloatArray:
        """swarm_iteration.explore(self, position, rng): fresh level-1 waypoints (k, 2) from
        positions (k, 2), the same draws, without the PolicyState that start builds around
        them (about 70 us a call, thousands of calls in a swarm block)."""
        if self._table is None:
            return explore(self, position, rng)
        start = np.array(position, dtype=float)
        return self._compiled_draw(
            self._table, np.zeros(len(start), dtype=np.intp), start.copy(), start, rng
        )

    def _compiled_draw(
        self,
        table: FloatArray,
        level: IntArray,
        anchor: FloatArray,
        position: FloatArray,
        rng: np.random.Generator,
    ) -> FloatArray:
        """next_waypoints for lanes at ``level`` with these anchors and positions."""
        return np.asarray(
            next_waypoints(
                table,
                level,
                anchor,
                np.ascontiguousarray(position, dtype=np.float64),
                self._bounds,
                RULES[self.config.out_of_area],
                self.config.waypoint_origin == "anchor",
                self.config.confine_to_detection,
                rng,
            )
        )
