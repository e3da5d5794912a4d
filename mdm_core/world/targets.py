"""Targets: fixed, pop-up (appear at a time), dynamic (the paper's random walk) and false.

Tracks are batched over independent runs. A dynamic target's path is stored on a grid of
nodes ``grid_dt`` apart and is linear between nodes. With ``grid_dt`` equal to the walk's
sampling time kappa_s every node is one step of eq. (2) with R(a, b) uniform; with a coarser grid
the increment over ``k`` steps is drawn from the normal law with the exact mean and variance of a
sum of ``k`` such steps (Irwin-Hall is within 1e-3 of normal for k >= 10). The grid grows on
demand, in fixed chunks, so the random stream does not depend on who asks for what.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from mdm_core.world.area import Area

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]
WalkBoundary = Literal["reflect", "clamp", "bounce", "free"]
CHUNK_NODES = 32
"""Path nodes drawn at a time (the random stream does not depend on how far runs go)."""
NODE_EPS = 1e-9
"""Slack on t / grid_dt when finding the segment that holds t (a time on a node is in the next)."""


@dataclass(frozen=True)
class TargetSpec:
    """Where targets start, when they appear and which are false."""

    positions: FloatArray
    """Start positions (m, 2), metres (north, east)."""
    appear_times: FloatArray
    """Time each target appears, seconds (0 for targets present from the start)."""
    false_mask: NDArray[np.bool_]
    """True for false targets: they trigger detection sensors, never the confirmation sensor."""

    def __post_init__(self) -> None:
        m = len(self.positions)
        if self.positions.shape != (m, 2):
            raise ValueError(f"target positions must have shape (m, 2), got {self.positions.shape}")
        if self.appear_times.shape != (m,) or self.false_mask.shape != (m,):
            raise ValueError("appear_times and false_mask need one entry per target")

    @property
    def count(self) -> int:
        return len(self.positions)

    @property
    def real_count(self) -> int:
        return int((~self.false_mask).sum())


@dataclass(frozen=True)
class RandomWalk:
    """The paper's dynamic-target model X(k+1) = X(k) + R(a, b) V_s kappa_s, eq. (2)."""

    speed: float = 5.0
    """V_s, m/s."""
    low: float = -0.2
    """a of R(a, b)."""
    high: float = 1.0
    """b of R(a, b)."""
    sample_time: float = 0.1
    """kappa_s, seconds."""
    shared_axes: bool = False
    """True: one R per step for both axes; False: an independent R per axis."""
    boundary: WalkBoundary = "reflect"
    """At a wall: mirror the position (reflect), stop at it (clamp), reverse the walk (bounce) or
    leave the area (free)."""

    def step_moments(self, steps: int) -> tuple[float, float]:
        """Mean and standard deviation of the displacement over ``steps`` samples, per axis."""
        scale = self.speed * self.sample_time
        mean = steps * scale * (self.low + self.high) / 2.0
        std = np.sqrt(steps) * scale * (self.high - self.low) / np.sqrt(12.0)
        return float(mean), float(std)


@dataclass
class TargetTracks:
    """Target positions over time for ``n_runs`` independent runs."""

    spec: TargetSpec
    area: Area
    n_runs: int
    rng: np.random.Generator
    walk: RandomWalk | None = None
    grid_dt: float = 10.0
    horizon: float = 0.0
    """Seconds of path to make room for at once (the caller's last time; 0: grow as asked).
    The room is reserved, not drawn, so the random stream does not depend on it; without it
    the buffers double as they fill, copying what is drawn."""
    _starts: FloatArray = field(init=False, repr=False)
    """(runs, capacity, m, 2): where segment k of each run's path starts (a grid node)."""
    _velocity: FloatArray = field(init=False, repr=False)
    """(runs, capacity, m, 2): the targets' velocity along segment k."""
    _filled: int = field(init=False, repr=False)
    """Segments drawn so far (the rest of the buffer is unused)."""
    _last: FloatArray = field(init=False, repr=False)
    """(runs, m, 2) the node that ends the last segment drawn."""
    _free: FloatArray = field(init=False, repr=False)
    _max_speed: float = field(init=False, repr=False, default=0.0)

    def __post_init__(self) -> None:
        start = np.broadcast_to(self.spec.positions, (self.n_runs, self.spec.count, 2))
        room = 0
        if self.walk is not None and self.horizon > 0:
            last = int(np.floor(self.horizon / self.grid_dt + NODE_EPS))
            room = (last // CHUNK_NODES + 1) * CHUNK_NODES
        self._starts = np.empty((self.n_runs, room, self.spec.count, 2))
        self._velocity = np.empty((self.n_runs, room, self.spec.count, 2))
        self._filled = 0
        self._last = np.array(start, dtype=float)
        self._free = np.array(start, dtype=float)
        if self.walk is not None:
            steps = self.grid_dt / self.walk.sample_time
            if steps < 1 - 1e-9 or abs(steps - round(steps)) > 1e-6:
                raise ValueError(
                    f"grid_dt {self.grid_dt} s must be a whole multiple of the walk's sample time "
                    f"{self.walk.sample_time} s"
                )

    @property
    def moving(self) -> bool:
        return self.walk is not None

    @property
    def filled(self) -> int:
        """Path segments drawn so far (``segments`` draws more)."""
        return self._filled

    @property
    def max_speed(self) -> float:
        """The highest target speed on any path segment drawn so far (0 for fixed targets)."""
        return self._max_speed

    def next_node_time(self, t: FloatArray) -> FloatArray:
        """The first grid node strictly after t (inf for fixed targets)."""
        if self.walk is None:
            return np.full_like(t, np.inf)
        return (np.floor(t / self.grid_dt + NODE_EPS) + 1.0) * self.grid_dt

    def positions(self, run: IntArray, t: FloatArray) -> FloatArray:
        """Target positions (n, m, 2) for lanes of the given runs at times t (n,)."""
        if self.walk is None:
            return np.broadcast_to(self.spec.positions, (len(run), self.spec.count, 2)).copy()
        pos, _ = self._interpolate(run, t)
        return pos

    def motion(self, run: IntArray, t: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Positions and velocities (n, m, 2) at t; both hold until ``next_node_time(t)``.

        Fixed targets give read-only broadcast views (no copy per call); moving ones new arrays.
        """
        shape = (len(run), self.spec.count, 2)
        if self.walk is None:
            return np.broadcast_to(self.spec.positions, shape), np.broadcast_to(0.0, shape)
        return self._interpolate(run, t)

    def segments(self, until: float) -> tuple[FloatArray, FloatArray]:
        """Every run's path as (runs, segments, m, 2) node positions and segment velocities,
        drawn at least up to the segment that holds time ``until``: the target at t is
        ``velocity[run, k] * (t - k * grid_dt) + start[run, k]`` with k as in ``motion``.
        Fixed targets: one segment, zero velocity, shared by every run (shape (1, 1, m, 2)).
        """
        if self.walk is None:
            start = self.spec.positions.reshape(1, 1, self.spec.count, 2).astype(float)
            return start, np.zeros_like(start)
        self._grow_to(int(np.floor(until / self.grid_dt + NODE_EPS)))
        return self._starts, self._velocity

    def departures(self, until: float) -> FloatArray:
        """(runs, m): when each target's path first leaves the area, inf if not by ``until``
        (and for fixed targets). Solved exactly on the linear segments: per segment and axis,
        the time the line reaches the wall it heads for, the earliest within its segment.
        Only a free walk leaves: the other boundaries keep every path inside (a clamped target
        that reaches a wall stays on it, and is not gone)."""
        out = np.full((self.n_runs, self.spec.count), np.inf)
        if self.walk is None or self.walk.boundary != "free":
            return out
        last = int(np.floor(until / self.grid_dt + NODE_EPS))
        size = self.area.size
        with np.errstate(divide="ignore", invalid="ignore"):
            for k in range(last + 1):
                if np.isfinite(out).all():
                    break  # every target has left: no need to draw the paths further
                starts, velocity = self.segments(k * self.grid_dt)
                s, v = starts[:, k], velocity[:, k]
                wall = np.where(v > 0, size, 0.0)
                hit = np.where(v != 0, (wall - s) / v, np.inf)  # (runs, m, 2), >= 0 inside
                hit = np.where(hit >= 0, hit, 0.0)  # a node already outside: gone at once
                at = k * self.grid_dt + hit.min(axis=-1)
                leaves = (hit.min(axis=-1) <= self.grid_dt) & np.isinf(out)
                out[leaves] = at[leaves]
        out[out > until] = np.inf
        return out

    def _grow_to(self, k: int) -> None:
        """Draw segments until segment k exists (the walk's draws come in the same order)."""
        while self._filled <= k:
            self._grow()

    def _interpolate(self, run: IntArray, t: FloatArray) -> tuple[FloatArray, FloatArray]:
        k = np.floor(t / self.grid_dt + NODE_EPS).astype(np.intp)
        self._grow_to(int(k.max(initial=0)))
        # Whole rows of the flattened (run, segment) axis: a plain take, no strided gather.
        row = run * self._starts.shape[1] + k
        width = self.spec.count * 2
        start = np.take(self._starts.reshape(-1, width), row, axis=0).reshape(
            -1, self.spec.count, 2
        )
        vel = np.take(self._velocity.reshape(-1, width), row, axis=0).reshape(start.shape)
        position = vel * (t - k * self.grid_dt)[:, None, None]
        position += start
        return position, vel

    def _increments(self) -> FloatArray:
        """The next chunk's displacements (runs, chunk, m, 1 or 2): one per axis, or one for
        both with shared_axes."""
        assert self.walk is not None
        walk = self.walk
        steps = round(self.grid_dt / walk.sample_time)
        shape = (self.n_runs, CHUNK_NODES, self.spec.count, 1 if walk.shared_axes else 2)
        if steps == 1:
            r = self.rng.uniform(walk.low, walk.high, size=shape)
            return np.asarray(r * walk.speed * walk.sample_time)
        mean, std = walk.step_moments(steps)
        return self.rng.normal(mean, std, size=shape)

    def _grow(self) -> None:
        increments = self._increments()
        increments = np.broadcast_to(increments, (*increments.shape[:3], 2))
        ends = self._walk(self._last, increments)
        end = self._filled + CHUNK_NODES
        if end > self._starts.shape[1]:
            self._starts = self._resized(self._starts, end)
            self._velocity = self._resized(self._velocity, end)
        # Segment k runs from node k to node k + 1; the chunk's first node is the last one drawn.
        starts = self._starts[:, self._filled : end]
        starts[:, 0] = self._last
        starts[:, 1:] = ends[:, :-1]
        velocity = self._velocity[:, self._filled : end]
        np.subtract(ends, starts, out=velocity)
        velocity /= self.grid_dt
        speed2 = float(np.max(velocity[..., 0] ** 2 + velocity[..., 1] ** 2, initial=0.0))
        self._max_speed = max(self._max_speed, float(np.sqrt(speed2)))
        self._filled = end
        self._last = ends[:, -1]

    def _resized(self, buffer: FloatArray, needed: int) -> FloatArray:
        """The buffer with room for ``needed`` segments (doubling), the drawn ones kept."""
        grown = np.empty((self.n_runs, max(needed, 2 * buffer.shape[1]), self.spec.count, 2))
        grown[:, : self._filled] = buffer[:, : self._filled]
        return grown

    def _walk(self, current: FloatArray, increments: FloatArray) -> FloatArray:
        """Positions (runs, k, m, 2) after each of the k increments from ``current``."""
        assert self.walk is not None
        rule = self.walk.boundary
        if rule in ("free", "bounce"):
            # The free path is a running sum (added in order, as a loop would); bounce folds it.
            origin = current if rule == "free" else self._free
            free = np.cumsum(np.concatenate([origin[:, None], increments], axis=1), axis=1)[:, 1:]
            if rule == "free":
                return free
            self._free = free[:, -1]
            return self.area.fold(free, "reflect")
        out = np.empty(increments.shape)
        size = self.area.size
        for i in range(increments.shape[1]):
            current = current + increments[:, i]
            outside = (current < 0.0) | (current > size)
            if outside.any():
                # Only points past a wall need the fold (clip or mirror); the rest are inside.
                folded = self.area.fold(current, "clip" if rule == "clamp" else "reflect")
                current = np.where(outside, folded, current)
            out[:, i] = current
        return out
