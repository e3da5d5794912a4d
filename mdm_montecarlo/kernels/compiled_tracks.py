"""The dynamic targets' paths for the batch engines, grown by one compiled loop (numba).

``TargetTracks._grow`` draws a chunk of displacements, then walks them (a running sum, the
fold into the area), writes the segments' start nodes and velocities and finds the top speed:
about a dozen numpy passes over (runs, chunk, targets, 2) arrays, each a fresh temporary, which
made the tracks about a sixth of the MDM rows' time (docs/model.md, "Speed of reproduce"). Here
the displacements are drawn by the same numpy call, and one loop per run and target does the
rest with the numpy version's operations in its order: the same paths bit for bit
(tests/montecarlo/test_compiled_tracks.py). The emulator and the companion keep TargetTracks.
"""

from __future__ import annotations

import json
import math
import threading
from collections import OrderedDict

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled
from mdm_core.world import Scenario, TargetTracks
from mdm_core.world.targets import CHUNK_NODES
from mdm_montecarlo.kernels.compiled_waypoints import clip

FloatArray = NDArray[np.float64]

FREE, BOUNCE, REFLECT, CLAMP = range(4)
_RULES = {"free": FREE, "bounce": BOUNCE, "reflect": REFLECT, "clamp": CLAMP}


class CompiledTracks(TargetTracks):
    """TargetTracks whose walk and segment writes run compiled; the draws are numpy's."""

    def _grow(self) -> None:
        assert self.walk is not None
        increments = self._increments()
        end = self._filled + CHUNK_NODES
        if end > self._starts.shape[1]:
            self._starts = self._resized(self._starts, end)
            self._velocity = self._resized(self._velocity, end)
        speed2 = _append(
            increments,
            self._last,
            self._free,
            self._starts,
            self._velocity,
            self._filled,
            _RULES[self.walk.boundary],
            self.area.size,
            self.grid_dt,
        )
        self._max_speed = max(self._max_speed, float(np.sqrt(speed2)))
        self._filled = end


def shared_tracks(
    scenario: Scenario, n_runs: int, rng: np.random.Generator, horizon: float
) -> TargetTracks:
    """compiled_tracks, drawn once per thread for every block that asks for the same paths.

    A block's targets are drawn from a stream of its own seed and block number whatever the
    configuration (common random numbers), so every configuration of a scenario with moving
    targets walks the same paths in block b: the first to ask draws them, the next ones read
    them (and draw further where they need to). The paths depend only on the targets' start
    points, the area, the walk, the grid, the number of runs and the stream's state; growing
    them in the same chunks from the same stream gives the same segments whoever asks, so
    results are those of tracks drawn afresh (tests/montecarlo/test_shared_tracks.py). The
    last ``KEPT`` are kept, per thread (a thread grows only its own)."""
    if scenario.walk is None:
        return compiled_tracks(scenario, n_runs, rng, horizon)
    spec = scenario.targets
    key = (
        spec.positions.tobytes(),
        spec.positions.shape,
        repr(scenario.area),
        repr(scenario.walk),
        scenario.grid_dt,
        n_runs,
        json.dumps(rng.bit_generator.state, sort_keys=True),
    )
    kept: OrderedDict[tuple[object, ...], TargetTracks] = _kept.__dict__.setdefault(
        "tracks", OrderedDict()
    )
    tracks = kept.get(key)
    if tracks is None:
        tracks = compiled_tracks(scenario, n_runs, rng, horizon)
        kept[key] = tracks
        while len(kept) > KEPT:
            kept.popitem(last=False)
    else:
        kept.move_to_end(key)
    return tracks


KEPT = 2
"""Paths kept per thread: every moving-target scenario of a study's block (about 50 MB each for
1000 runs to reproduce's 40 000 s cap)."""
_kept = threading.local()


def compiled_tracks(
    scenario: Scenario, n_runs: int, rng: np.random.Generator, horizon: float
) -> TargetTracks:
    """Scenario.tracks(n_runs, rng, horizon), grown by the compiled loop."""
    return CompiledTracks(
        scenario.targets, scenario.area, n_runs, rng, scenario.walk, scenario.grid_dt, horizon
    )


@compiled
def _fold(x: float, size: float) -> float:
    """Area.fold(..., 'reflect') of one coordinate."""
    period = 2.0 * size
    folded = x - math.floor(x / period) * period
    return min(folded, period - folded)


@compiled
def _append(
    increments: FloatArray,
    last: FloatArray,
    free: FloatArray,
    starts: FloatArray,
    velocity: FloatArray,
    filled: int,
    rule: int,
    size: FloatArray,
    grid_dt: float,
) -> float:
    """Walk the chunk of ``increments`` from the ``last`` nodes (``free``: the unfolded
    path's end, for bounce), write segments ``filled`` onwards into ``starts`` and
    ``velocity``, update ``last`` and ``free`` in place; returns the top squared speed."""
    runs, chunk, m, axes = increments.shape
    top = 0.0
    for r in range(runs):
        for j in range(m):
            for c in range(chunk):
                k = filled + c
                for a in range(2):
                    step = increments[r, c, j, a if axes == 2 else 0]
                    start = last[r, j, a]
                    if rule == FREE:
                        node = start + step
                    elif rule == BOUNCE:
                        free[r, j, a] = free[r, j, a] + step
                        node = _fold(free[r, j, a], size[a])
                    else:
                        node = start + step
                        if node < 0.0 or node > size[a]:
                            node = _fold(node, size[a]) if rule == REFLECT else clip(node, size[a])
                    starts[r, k, j, a] = start
                    velocity[r, k, j, a] = (node - start) / grid_dt
                    last[r, j, a] = node
                vx = velocity[r, k, j, 0]
                vy = velocity[r, k, j, 1]
                top = max(top, vx * vx + vy * vy)
    return top
