"""Social-cognitive baselines of section IV (PSO, SPSO, ARPSO) as pure, batched update rules.

Each UAV is a particle; its fitness is the signal strength its sensor reads from the strongest
target it does not know to be confirmed (0 when it reads nothing). One call of ``next_step`` is
one PSO iteration: it returns each particle's displacement for the next ``update_interval``,
clamped to what the UAV can fly in that time. The sharing is an explicit input: the caller hands
every particle the best it has heard of (``swarm_best`` over the messages it received), so the
same rules run in the Monte-Carlo engine (shared state of a run, with optional delay and loss)
and in a live companion (messages from a broker).

Update rules, in metres per iteration (sources and choices in docs/model.md):

- PSO, inertia weight (Kennedy & Eberhart 1995; Shi & Eberhart 1998):
  u <- w u + c1 r1 (p - x) + c2 r2 (g - x), r1, r2 ~ U(0, 1) per axis.
- SPSO-2011 (Clerc 2012; Zambrano-Bigiarini, Clerc & Rojas 2013): centre of gravity
  G = x + c (p + l - 2x) / 3 (G = x + c (p - x) / 2 when the particle is its own local best),
  x' uniform in the disc of centre G and radius |G - x|, u <- w u + x' - x; l is the best of the
  particle's informants (adaptive random topology).
- ARPSO (A-RPSO, Dadgar, Jafari & Hamzeh 2016): the PSO rule with a per-particle inertia
  w_i = w_ini - alpha (1 - h_i) + beta s (evolution speed factor h_i, aggregation degree s,
  after Yang et al. 2007). Its obstacle term is zero: there are no obstacles in this search and
  UAVs are separated in altitude (Assumption III).

Compiled twin: mdm_montecarlo/kernels/swarm_kernels.py, the same rules operation for operation
(tests/montecarlo/test_swarm_kernels.py); a change here is made there too.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from mdm_core.search.planar import length

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]
Variant = Literal["pso", "spso", "arpso"]
VARIANTS: tuple[Variant, ...] = ("pso", "spso", "arpso")


@dataclass(frozen=True)
class SwarmConfig:
    """Coefficients of one variant; steps are metres per iteration."""

    variant: Variant
    max_step: float
    """Velocity clamp: the UAV speed times the update interval, metres."""
    constant_speed: bool = True
    """Every step is max_step long (Assumption II: all UAVs fly at V_U); False: clamp only."""
    inertia: float = 0.7298
    cognitive: float = 1.49618
    social: float = 1.49618
    spso_inertia: float = 0.7213
    spso_acceleration: float = 1.1931
    arpso_initial_inertia: float = 1.0
    arpso_speed_weight: float = 0.5
    arpso_aggregation_weight: float = 0.4

    def __post_init__(self) -> None:
        if self.variant not in VARIANTS:
            raise ValueError(f"unknown swarm variant {self.variant!r}; allowed: {VARIANTS}")
        if not self.max_step > 0:
            raise ValueError(f"max_step must be > 0 m, got {self.max_step}")


@dataclass
class Best:
    """A best position with its fitness and the target its signal came from (arrays)."""

    position: FloatArray
    """(..., 2) metres."""
    fitness: FloatArray
    """(...) signal strength at that position; 0 = no best."""
    source: IntArray
    """(...) index of the target that gave the signal; -1 = none."""

    def copy(self) -> Best:
        return Best(self.position.copy(), self.fitness.copy(), self.source.copy())


def signal_fitness(strength: FloatArray, usable: BoolArray) -> tuple[FloatArray, IntArray]:
    """Fitness (strongest usable signal, 0 if none) and its source target, over the last axis."""
    masked = np.where(usable, strength, 0.0)
    source = np.argmax(masked, axis=-1)
    fitness = _take_last(masked, source)
    return fitness, np.where(fitness > 0, source, -1).astype(np.intp)


def improve(best: Best, position: FloatArray, fitness: FloatArray, source: IntArray) -> Best:
    """Personal bests after reading ``fitness`` at ``position`` (strictly better replaces)."""
    better = fitness > best.fitness
    return Best(
        np.where(better[..., None], position, best.position),
        np.where(better, fitness, best.fitness),
        np.where(better, source, best.source),
    )


def forget(best: Best, known: BoolArray) -> Best:
    """Bests whose source target is known to be confirmed are dropped (fitness 0, source -1).

    ``known`` has the shape of ``best.fitness`` plus a last axis over targets.
    """
    stale = (best.source >= 0) & _take_last(known, np.maximum(best.source, 0))
    return Best(
        best.position,
        np.where(stale, 0.0, best.fitness),
        np.where(stale, -1, best.source).astype(np.intp),
    )


def swarm_best(own: Best, heard: Best, links: BoolArray) -> tuple[Best, BoolArray]:
    """Best of a particle's own best and the bests it heard from linked particles.

    own: (..., ) fields; heard: (..., k) fields, one slot per other particle; links (..., k):
    which slots count (the whole swarm for PSO/ARPSO, the informants for SPSO). Returns the
    best and True where it is the particle's own (ties go to the particle's own best).
    """
    candidates = np.where(links, heard.fitness, -np.inf)
    slot = np.argmax(candidates, axis=-1)
    other = _take_last(candidates, slot)
    mine = own.fitness >= other
    position = _take_point(heard.position, slot)
    source = _take_last(heard.source, slot)
    best = Best(
        np.where(mine[..., None], own.position, position),
        np.where(mine, own.fitness, other),
        np.where(mine, own.source, source).astype(np.intp),
    )
    return best, mine


def _take_last(values: NDArray[Any], index: IntArray) -> NDArray[Any]:
    """values[..., index] at every leading position: values (..., k) (leading axes broadcast
    to those of index), index (...) in [0, k). One flat gather."""
    k = values.shape[-1]
    flat = np.ascontiguousarray(np.broadcast_to(values, (*index.shape, k))).reshape(-1)
    return flat[np.arange(0, index.size * k, k).reshape(index.shape) + index]


def _take_point(points: FloatArray, slot: IntArray) -> FloatArray:
    """points[..., slot, :] of points (..., k, 2), shape (..., 2); each point is taken as one
    complex number."""
    as_complex = np.ascontiguousarray(points, dtype=np.float64).view(np.complex128)[..., 0]
    return _take_last(as_complex, slot)[..., None].view(np.float64)


def clamp(step: FloatArray, max_step: float, constant_speed: bool = False) -> FloatArray:
    """Steps (..., 2) scaled to at most (constant_speed: exactly) ``max_step`` metres, same
    direction. A zero step stays zero."""
    size = length(step)[..., None]
    scaled = max_step / np.where(size > 0, size, 1.0)
    too_long = size > max_step
    if constant_speed:
        too_long = size > 0
    return np.asarray(step * np.where(too_long, scaled, 1.0))


def pso_step(
    step: FloatArray,
    position: FloatArray,
    personal: FloatArray,
    social: FloatArray,
    inertia: FloatArray | float,
    c1: float,
    c2: float,
    rng: np.random.Generator,
) -> FloatArray:
    """Inertia-weight PSO: w u + c1 r1 (p - x) + c2 r2 (g - x), before clamping."""
    r1 = rng.random(position.shape)
    r2 = rng.random(position.shape)
    w = np.asarray(inertia, dtype=float)[..., None] if np.ndim(inertia) else inertia
    return np.asarray(w * step + c1 * r1 * (personal - position) + c2 * r2 * (social - position))


def spso_step(
    step: FloatArray,
    position: FloatArray,
    personal: FloatArray,
    local: FloatArray,
    own_is_local: BoolArray,
    inertia: float,
    acceleration: float,
    rng: np.random.Generator,
) -> FloatArray:
    """SPSO-2011: w u + x' - x, x' uniform in the disc around the centre of gravity G."""
    c = acceleration
    with_local = position + c * (personal + local - 2.0 * position) / 3.0
    alone = position + c * (personal - position) / 2.0
    centre = np.where(own_is_local[..., None], alone, with_local)
    radius = length(centre - position)
    direction = rng.standard_normal(position.shape)
    norm = length(direction)[..., None]
    direction = direction / np.where(norm > 0, norm, 1.0)
    reach = radius * np.sqrt(rng.random(radius.shape))
    sample = centre + direction * reach[..., None]
    return np.asarray(inertia * step + sample - position)


def arpso_inertia(
    previous_best: FloatArray,
    best: FloatArray,
    swarm_now_best: FloatArray,
    swarm_now_mean: FloatArray,
    initial: float,
    speed_weight: float,
    aggregation_weight: float,
) -> FloatArray:
    """A-RPSO inertia w_ini - alpha (1 - h) + beta s for a fitness to maximise.

    h = min(f(p_prev), f(p)) / max(f(p_prev), f(p)): 1 when the personal best did not move
    (slow evolution), small when it jumped. s = min(f_mean, f_best) / max(f_mean, f_best) of the
    swarm's current fitness: 1 when every particle reads the same (aggregated). Both are 1 when
    their denominator is 0 (nothing read yet).
    """

    def ratio(a: FloatArray, b: FloatArray) -> FloatArray:
        hi = np.maximum(a, b)
        return np.asarray(np.where(hi > 0, np.minimum(a, b) / np.where(hi > 0, hi, 1.0), 1.0))

    h = ratio(previous_best, best)
    s = ratio(swarm_now_mean, swarm_now_best)
    return np.asarray(initial - speed_weight * (1.0 - h) + aggregation_weight * s)


def random_informants(
    rng: np.random.Generator, shape: tuple[int, ...], n: int, k: int
) -> BoolArray:
    """Adaptive random topology: (*shape, n, n) links, row i = the k particles i listens to.

    Every particle draws ``k`` informants other than itself uniformly without replacement
    (all others when k >= n - 1): the k with the smallest of n uniform keys (ties between keys
    have probability 0), its own key set to inf.
    """
    keys = rng.random((*shape, n, n))
    keys[..., np.arange(n), np.arange(n)] = np.inf
    k = min(k, n - 1)
    if k == 0:
        return np.zeros((*shape, n, n), dtype=bool)
    kth = np.partition(keys, k - 1, axis=-1)[..., k - 1, None]
    return np.asarray(keys <= kth)


def next_step(
    config: SwarmConfig,
    step: FloatArray,
    position: FloatArray,
    personal: Best,
    social: Best,
    own_is_social: BoolArray,
    inertia: FloatArray | None,
    rng: np.random.Generator,
) -> FloatArray:
    """One iteration of the configured variant, clamped to (or flown at) ``config.max_step``.

    ``social`` is the swarm (PSO, ARPSO) or informant (SPSO) best from ``swarm_best``;
    ``inertia`` is the per-particle ARPSO weight (``arpso_inertia``), ignored otherwise.
    A best of fitness 0 (nothing read yet) pulls nowhere: the particle stands in for it.
    """
    mine = np.where((personal.fitness > 0)[..., None], personal.position, position)
    theirs = np.where((social.fitness > 0)[..., None], social.position, mine)
    if config.variant == "spso":
        raw = spso_step(
            step,
            position,
            mine,
            theirs,
            own_is_social,
            config.spso_inertia,
            config.spso_acceleration,
            rng,
        )
    else:
        w: FloatArray | float = config.inertia
        if config.variant == "arpso":
            if inertia is None:
                raise ValueError("ARPSO needs the per-particle inertia (arpso_inertia)")
            w = inertia
        raw = pso_step(
            step,
            position,
            mine,
            theirs,
            w,
            config.cognitive,
            config.social,
            rng,
        )
    return clamp(raw, config.max_step, config.constant_speed)
