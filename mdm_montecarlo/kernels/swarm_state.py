"""The named structures the waypoint swarm's kernels pass (``waypoint_rounds``,
``waypoint_legs``, ``waypoint_kernels``): a configuration's swarm, the stepped loop, the
particles, the targets as they sense them, the confirmations and the arrivals, each a
NamedTuple numba reads field by field. Moving one of these classes to another module voids the
kernels' disk cache (mdm_core/jit.py)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from mdm_montecarlo.kernels.policy_waypoints import Draws

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]


class Swarm(NamedTuple):
    """A configuration's swarm as the kernels read it, built once per configuration."""

    variant: int
    """PSO, SPSO or ARPSO."""
    rules: FloatArray
    """Its constants, in the order of RULE_COLUMNS."""
    informants: int
    """SPSO: the informants each particle links to."""
    draws: Draws
    """The explorers' level-1 waypoint draws."""


class Steps(NamedTuple):
    """The time-stepped loop the waypoint swarm reproduces, and the area its particles fly in."""

    times: FloatArray
    """Every step's time, seconds (waypoint_swarm._step_times)."""
    dt: float
    distance: float
    """Metres a particle flies in one step."""
    past_duration: int
    """The first step past the mission duration (the loop may stop from there on)."""
    area: FloatArray
    """The area's (north, east) size, metres."""


class Particles(NamedTuple):
    """Every particle's arrays, (runs, vehicles, ...), updated in place."""

    position: FloatArray
    waypoint: FloatArray
    velocity: FloatArray
    own_position: FloatArray
    own_fitness: FloatArray
    own_source: IntArray
    reading: FloatArray
    """Its reading at its last waypoint."""
    source: IntArray
    """The target that reading came from (-1: none)."""
    current: FloatArray
    """The reading as its current fitness (ARPSO's aggregation degree)."""
    links: BoolArray
    """(runs, vehicles, vehicles) whom each particle hears."""
    local_fitness: FloatArray
    """SPSO: the local best each particle steered by at its last arrival."""


class Sensing(NamedTuple):
    """The targets as the particles sense and confirm them."""

    seg_start: FloatArray
    seg_velocity: FloatArray
    grid_dt: float
    moving: bool
    top_speed: float
    appear: FloatArray
    real: BoolArray
    confirm_radius: float
    signal_radius: float
    near: float
    """Squared metres within which a reading counts as at the target."""
    unread_known: bool
    """A run's confirmed targets give no more readings (not policy.swarm.read_confirmed)."""
    forget: bool
    """Forget the bests of confirmed targets (after_confirmation: forget)."""


class Found(NamedTuple):
    """The confirmations, updated in place (waypoint_legs.walk_legs)."""

    known_step: IntArray
    """(runs, m) the step at which each run first confirms each target."""
    conf_time: FloatArray
    """(lanes, m) each particle's first confirmation time."""
    conf_step: IntArray
    """(lanes, m) and its step."""


class Arrivals(NamedTuple):
    """Where and when each particle's leg ends (waypoint_legs.walk_legs writes them)."""

    step: IntArray
    """(lanes,) the step it arrives at (len(times): it does not)."""
    position: FloatArray
    """(lanes, 2) where it is then."""
