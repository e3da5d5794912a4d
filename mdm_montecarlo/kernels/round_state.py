"""The named structures the batch engine's rounds pass between their kernels (``block_rounds``,
``round_kernels``, ``remembered``): numba reads a NamedTuple of arrays and numbers field by
field at compile time, so handing a kernel four of them costs what its forty arguments cost
(benchmarks/README.md, "Kernel signatures"). Moving one of these classes to another module
voids the kernels' disk cache (mdm_core/jit.py)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]


class Block(NamedTuple):
    """What stays fixed over a block's rounds: its fleet and mission, and which of its targets
    are false and when each appears."""

    n_vehicles: int
    speed: float
    """The vehicles' speed, m/s."""
    duration: float
    """mission.duration, seconds: no run stops before."""
    cap: float
    """The latest stop of any run: max(mission.ts_cap, duration)."""
    false_mask: BoolArray
    appear: FloatArray
    real: BoolArray


class Flight(NamedTuple):
    """Every lane's flight (lanes = runs x vehicles) and every run's end, updated in place."""

    position: FloatArray
    """(lanes, 2) metres."""
    time: FloatArray
    """(lanes,) seconds."""
    active: BoolArray
    """(lanes,) whether the lane flies on."""
    first: FloatArray
    """(lanes, m) its first confirmation of each target, seconds (inf: none yet)."""
    stop: FloatArray
    """(runs,) when each run ends."""
    gone: FloatArray
    """(runs, m) when each target left the area (inf: never, or T_S counts confirmations)."""


class Paths(NamedTuple):
    """The targets' paths as drawn so far (TargetTracks.segments), for one call of the rounds."""

    seg_start: FloatArray
    seg_velocity: FloatArray
    filled: int
    """Path segments drawn: a leg ending past them needs the tracks grown first."""
    grid_dt: float
    moving: bool
    visible: float
    """The tracks' top speed before the last growth (what the remembered windows check)."""
    grown: float
    """Their top speed after it (what the entry times use)."""


class Stepped(NamedTuple):
    """The lanes a round moves: their indices, runs and times, and whether each checks its
    memory exactly (memory rule 'exact', or on the confirmation level)."""

    lanes: IntArray
    runs: IntArray
    t: FloatArray
    exact: BoolArray


class Legs(NamedTuple):
    """Each stepped lane's leg, written by ``round_kernels.legs``."""

    unit: FloatArray
    """(n, 2) the unit vector to the waypoint."""
    leg: FloatArray
    """(n,) seconds to the waypoint."""
    left: FloatArray
    """(n,) seconds to the level's deadline."""
    horizon: FloatArray
    """(n,) seconds the lane may fly before an event that needs no sensing."""


class Events(NamedTuple):
    """What ``round_kernels.advance`` reads and writes per stepped lane."""

    eligible: BoolArray
    """(n, m) in: the targets each lane may sense (cleared further in place)."""
    entry: FloatArray
    """(m,) scratch: one lane's entry times."""
    reached: BoolArray
    """(n,) out: the lane reached its waypoint."""
    contacts: BoolArray
    """(n, m) out: the targets sensed at the event."""
    where: FloatArray
    """(n, m, 2) out: the contacted (and detected) targets' positions."""
    detections: BoolArray
    """(n, m) out: with a redetection rule, what the detection sensor reports on the last
    level at the event (else not written)."""
