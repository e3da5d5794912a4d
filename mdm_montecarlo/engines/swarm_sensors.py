"""The targets as the particles of the swarm engines sense and confirm them
(mdm_montecarlo.engines.social_engine, mdm_montecarlo.engines.waypoint_swarm): batched over (runs, vehicles),
the vehicles of a run sharing its targets."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mdm_core.world import TargetTracks
from mdm_montecarlo.kernels import swarm_kernels as kernels
from mdm_montecarlo.kernels.pair_entry import pair_entry_times

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]


@dataclass(frozen=True)
class SwarmSensors:
    """The targets as the vehicles of a block sense them; the vehicles of a run share them."""

    tracks: TargetTracks
    runs: IntArray
    """Every run of the block, 0 .. runs - 1."""
    real: BoolArray
    """(targets,) True for real targets (the only ones that can be confirmed)."""
    appear: FloatArray
    """(targets,) appearance times, s."""
    confirm_radius: float
    signal_radius: float
    dt: float
    """Update interval, s."""

    def motion(self, t: float) -> TargetsNow:
        """Every run's targets at time t."""
        target, velocity = self.tracks.motion(self.runs, np.full(len(self.runs), t))
        return TargetsNow(target, velocity, t, self.dt * _length_bound(velocity))

    def sense(
        self,
        targets: TargetsNow,
        position: FloatArray,
        known: BoolArray,
        rows: BoolArray,
        fitness: FloatArray,
        source: IntArray,
        nearest: FloatArray,
    ) -> None:
        """The fitness and its source (mdm_core.search.pso.signal_fitness) at ``position``
        (runs, vehicles, 2) of every vehicle where ``rows``, in place: the signal sensor's
        strongest exp(-d / R) of a present target within R that the vehicle does not know to
        be confirmed (as mdm_core.world.contacts reads it); strengths are computed only for the
        pairs nearer than R (a superset from the squared distances). ``nearest``: every
        vehicle's smallest squared distance to a real target, for confirm."""
        radius = self.signal_radius
        kernels.sense(
            targets.position,
            position,
            self.appear,
            targets.t,
            radius,
            radius * radius * NEAR,
            known,
            self.real,
            rows,
            fitness,
            source,
            nearest,
        )

    def confirm(
        self,
        targets: TargetsNow,
        position: FloatArray,
        nearest: FloatArray,
        step: FloatArray,
        longest: float,
        first: FloatArray,
        known: BoolArray,
    ) -> tuple[IntArray, IntArray]:
        """Confirm the real targets whose disc the segments ``position`` -> ``position + step``
        (runs, vehicles, 2), flown from targets.t to targets.t + dt, enter: ``first`` and
        ``known`` (runs, vehicles, targets) are updated in place. ``nearest``: from
        sense(targets, position, ...); ``longest``: the largest absolute coordinate of a step.
        Returns the (run, target) of every confirmation.

        The closed form (mdm_core.world.first_entry_time, compiled per pair in
        mdm_montecarlo.kernels.pair_entry) is solved only for the vehicle x target pairs that can meet
        in the interval: those no farther apart than confirm_radius + the longest step + the
        farthest a target moves in dt.
        """
        t = targets.t
        travel = math.sqrt(2.0) * longest + targets.travel
        # The slack covers the rounding of the closed form; it only adds pairs to solve.
        reach = self.confirm_radius + travel + _SLACK
        run, lane, index = kernels.open_pairs(
            targets.position, position, nearest, reach * reach, self.real, known
        )
        if len(run) == 0:
            return run, index
        entry = pair_entry_times(
            position[run, lane],
            step[run, lane] / self.dt,
            self.dt,
            targets.position[run, index],
            targets.velocity[run, index],
            self.confirm_radius,
            self.appear[index] - t,
        )
        hit = entry <= self.dt
        run, lane, index = run[hit], lane[hit], index[hit]
        first[run, lane, index] = np.minimum(first[run, lane, index], t + entry[hit])
        known[run, lane, index] = True
        return run, index


@dataclass(frozen=True)
class TargetsNow:
    """Every run's targets at one time: (runs, targets, 2) positions and velocities, both
    holding until the next node of their tracks."""

    position: FloatArray
    velocity: FloatArray
    t: float
    travel: float
    """dt x a bound of the targets' speeds: at most how far one moves in an interval."""


_SLACK = 1.0
"""Metres added to the reach of a confirmation step (rounding margin, far above it)."""
NEAR = 1.0 + 1e-9
"""Relative margin on R^2 so that the pairs nearer than R are all kept despite rounding."""


def _length_bound(vectors: FloatArray) -> float:
    """An upper bound of the lengths of vectors (..., 2): sqrt(2) x the largest coordinate."""
    return math.sqrt(2.0) * float(np.abs(vectors).max(initial=0.0))
