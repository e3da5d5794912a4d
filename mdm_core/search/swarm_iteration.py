"""One iteration of the social-cognitive baselines around the pure rules of pso.py.

What the Monte-Carlo engine (mdm_montecarlo.engines.social_engine, batched over runs x vehicles) and
the live companion (companion.mission.swarm_core, one vehicle) both do each update interval:
pick the move (the PSO step of the variant when the particle has a best to follow, else the
single-sensor exploration of the profile's level 1), take a new reading into the personal best,
and, for SPSO, redraw the informants of particles whose local best did not improve. Shapes are
the engine's (..., particles) with heard tables (..., particles, vehicles); the live vehicle is
a batch of one.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from mdm_core.search.planar import length
from mdm_core.search.policy import SearchPolicy
from mdm_core.search.pso import (
    Best,
    BoolArray,
    FloatArray,
    IntArray,
    SwarmConfig,
    arpso_inertia,
    forget,
    improve,
    next_step,
    swarm_best,
)

BestOf = Callable[[Best, Best, BoolArray], tuple[Best, BoolArray]]
"""swarm_best(own, heard, links), or a faster equivalent for the caller's heard tables."""


def explore(policy: SearchPolicy, position: FloatArray, rng: np.random.Generator) -> FloatArray:
    """Fresh level-1 waypoints (k, 2) of the single-sensor search from positions (k, 2)."""
    return policy.start(position, np.zeros(len(position)), rng).waypoint


def arpso_weights(
    config: SwarmConfig,
    previous_best: FloatArray,
    own: Best,
    current: FloatArray,
    heard_current: FloatArray,
    links: BoolArray,
) -> FloatArray | None:
    """ARPSO per-particle inertia from the particle's own and its linked peers' current
    readings (None for PSO and SPSO, which do not use it)."""
    if config.variant != "arpso":
        return None
    # The particle's own reading, then its linked peers' (0 for the others).
    reads = np.zeros((*current.shape, 1 + heard_current.shape[-1]))
    reads[..., 0] = current
    np.copyto(reads[..., 1:], heard_current, where=links)
    now_best = reads.max(axis=-1)
    now_mean = reads.sum(axis=-1) / (1 + links.sum(axis=-1))
    return arpso_inertia(
        previous_best,
        own.fitness,
        now_best,
        now_mean,
        config.arpso_initial_inertia,
        config.arpso_speed_weight,
        config.arpso_aggregation_weight,
    )


def choose_move(
    config: SwarmConfig,
    explorer: SearchPolicy,
    *,
    position: FloatArray,
    step: FloatArray,
    waypoint: FloatArray,
    guided: BoolArray,
    own: Best,
    heard: Best,
    heard_current: FloatArray,
    current: FloatArray,
    previous_best: FloatArray,
    links: BoolArray,
    distance: float,
    rng: np.random.Generator,
) -> tuple[FloatArray, BoolArray, BoolArray]:
    """The displacement (..., 2) for the next interval, which particles follow a best, and
    which of them follow a peer's best rather than their own.

    ``step``: last displacement; ``waypoint``: exploration waypoints, updated in place where a
    particle that followed a best (``guided``) has none left; ``distance``: how far a particle
    flies in one interval (speed x interval).
    """
    social, own_is_social = swarm_best(own, heard, links)
    follow = social.fitness > 0
    inertia = arpso_weights(config, previous_best, own, current, heard_current, links)
    swarm_move = next_step(config, step, position, own, social, own_is_social, inertia, rng)
    # Particles that lost their best go back to exploring from where they are.
    lost = guided & ~follow
    if lost.any():
        waypoint[lost] = explore(explorer, position[lost], rng)
    to_waypoint = waypoint - position
    gap = length(to_waypoint)[..., None]
    explore_move = to_waypoint * np.minimum(1.0, distance / np.maximum(gap, 1e-12))
    move = np.where(follow[..., None], swarm_move, explore_move)
    return move, follow, follow & ~own_is_social


def read_into_best(
    own: Best, known: BoolArray, position: FloatArray, fitness: FloatArray, source: IntArray
) -> tuple[Best, FloatArray]:
    """Personal bests after a reading: bests of known-confirmed targets dropped, then improved.

    Returns the bests and the fitness of the (kept) best before the reading (ARPSO's h)."""
    own = forget(own, known)
    previous_best = own.fitness.copy()
    return improve(own, position, fitness, source), previous_best


def refresh_informants(
    own: Best,
    heard: Best,
    links: BoolArray,
    local_fitness: FloatArray,
    draw: Callable[[], BoolArray],
    best_of: BestOf = swarm_best,
) -> tuple[BoolArray, FloatArray]:
    """SPSO adaptive random topology: new informants (``draw()``, the shape of ``links``) where
    the local best did not improve on ``local_fitness``. Returns the links and the local bests'
    fitness to compare with next time."""
    updated, _ = best_of(own, heard, links)
    stuck = updated.fitness <= local_fitness
    if stuck.any():
        links = np.where(stuck[..., None], draw(), links)
    return links, updated.fitness
