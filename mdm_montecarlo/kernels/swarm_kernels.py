"""Compiled (numba) pieces of one iteration of the swarm baselines (mdm_montecarlo.engines.social_engine).

The time-stepped engine moves (runs, vehicles) particles through a dozen small numpy passes per
step (sensing, swarm bests, the PSO rules, personal bests, SPSO's informants), each allocating
(runs, vehicles, ...) temporaries; those passes were most of the engine's time. Here each is one
loop over the particles. Every operation is the numpy version's (mdm_core.search.pso and
swarm_iteration, the engine's former passes), in its order, and the random numbers are the
same arrays, drawn by the caller with numpy (faster than numba's draws one at a time), so
results are bit-identical (tests/montecarlo/test_swarm_kernels.py compares them
with the numpy rules on random states). The signal strength's exp is the C library's, as in
every compiled kernel: numpy's own exp rounds differently on CPUs with AVX-512 (mdm_core.libm),
so on those machines the swarm rows differ from the numpy engine's before this module.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled
from mdm_core.world.sensors import THRESHOLD

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]


@compiled
def sense(
    target: FloatArray,
    position: FloatArray,
    appear: FloatArray,
    t: float,
    radius: float,
    near: float,
    known: BoolArray,
    real: BoolArray,
    rows: BoolArray,
    fitness: FloatArray,
    source: IntArray,
    nearest: FloatArray,
) -> None:
    """The fitness and its source of every vehicle where ``rows`` (runs, vehicles), in place in
    ``fitness`` and ``source`` (the others' are left as they are), from ``position`` (runs,
    vehicles, 2) and ``target`` (runs, targets, 2): the strongest exp(-d / radius) above
    THRESHOLD of a present target within ``radius`` it does not know to be confirmed (0 and -1
    if none), as mdm_core.search.pso.signal_fitness picks it. Strengths are computed only for
    squared distances below ``near`` (radius^2 with a rounding margin). ``nearest``, for every
    vehicle: the smallest squared distance to a ``real`` target (inf if none), the squares
    rounded as mdm_core.world.contacts rounds them (_gap)."""
    runs, n, m = known.shape
    for r in range(runs):
        for i in range(n):
            read = rows[r, i]
            best = 0.0
            found = -1
            closest = np.inf
            for k in range(m):
                gap = _gap(target, position, r, i, k)
                if real[k] and gap < closest:
                    closest = gap
                # The strength only where the target could be read (the cheap tests first).
                if read and gap < near and appear[k] <= t and not known[r, i, k]:
                    strength = signal(gap, radius)
                    if strength > best:
                        best = strength
                        found = k
            if read:
                fitness[r, i] = best
                source[r, i] = found
            nearest[r, i] = closest


@partial(compiled, inline=True)
def signal(gap: float, radius: float) -> float:
    """The signal sensor's reading of a target ``gap`` (squared metres) away: exp(-d / radius)
    within ``radius`` where it is above THRESHOLD, else 0 (mdm_core.search.pso.signal_fitness's
    strength, the C library's exp)."""
    distance = math.sqrt(gap)
    if distance < radius:
        strength = math.exp(-distance / radius)
        if strength > THRESHOLD:
            return strength
    return 0.0


@compiled
def _gap(target: FloatArray, position: FloatArray, r: int, i: int, k: int) -> float:
    """Squared distance from vehicle i to target k of run r."""
    dx: float = target[r, k, 0] - position[r, i, 0]
    dy: float = target[r, k, 1] - position[r, i, 1]
    return dx * dx + dy * dy


@compiled
def open_pairs(
    target: FloatArray,
    position: FloatArray,
    nearest: FloatArray,
    reach2: float,
    real: BoolArray,
    known: BoolArray,
) -> tuple[IntArray, IntArray, IntArray]:
    """(run, vehicle, target) indices, in row-major order, of the pairs no farther apart than
    sqrt(reach2) whose target is real and not yet known to that vehicle to be confirmed.
    ``nearest``: sense's for these positions and targets; only the vehicles with a real target
    within reach are looked at, their squared distances computed again (the same floats)."""
    _, n, m = known.shape
    close = np.flatnonzero(nearest.ravel() <= reach2)
    run = np.empty(close.size * m, dtype=np.intp)
    lane = np.empty(close.size * m, dtype=np.intp)
    index = np.empty(close.size * m, dtype=np.intp)
    count = 0
    for flat in close:
        r, i = divmod(flat, n)
        for k in range(m):
            if _gap(target, position, r, i, k) <= reach2 and real[k] and not known[r, i, k]:
                run[count] = r
                lane[count] = i
                index[count] = k
                count += 1
    return run[:count], lane[:count], index[:count]


@compiled
def forget_known(fitness: FloatArray, source: IntArray, known: BoolArray) -> None:
    """mdm_core.search.pso.forget in place: bests (runs, vehicles) whose source target the
    vehicle knows to be confirmed get fitness 0 and source -1."""
    runs, n = fitness.shape
    for r in range(runs):
        for i in range(n):
            if source[r, i] >= 0 and known[r, i, source[r, i]]:
                fitness[r, i] = 0.0
                source[r, i] = -1


@compiled
def read_into_best(
    position: FloatArray,
    fitness: FloatArray,
    source: IntArray,
    known: BoolArray,
    at: FloatArray,
    reading: FloatArray,
    reading_source: IntArray,
) -> FloatArray:
    """mdm_core.search.swarm_iteration.read_into_best in place on the personal bests
    (``position``, ``fitness``, ``source``): forget, then a strictly better ``reading`` at
    ``at`` replaces. Returns the fitness of the kept bests before the reading (ARPSO's h)."""
    forget_known(fitness, source, known)
    previous = fitness.copy()
    runs, n = fitness.shape
    for r in range(runs):
        for i in range(n):
            if reading[r, i] > fitness[r, i]:
                position[r, i, 0] = at[r, i, 0]
                position[r, i, 1] = at[r, i, 1]
                fitness[r, i] = reading[r, i]
                source[r, i] = reading_source[r, i]
    return previous


@compiled
def swarm_best(
    own_position: FloatArray,
    own_fitness: FloatArray,
    own_source: IntArray,
    heard_position: FloatArray,
    heard_fitness: FloatArray,
    heard_source: IntArray,
    links: BoolArray,
) -> tuple[FloatArray, FloatArray, IntArray, BoolArray]:
    """mdm_core.search.pso.swarm_best for own (runs, vehicles) and heard (runs, vehicles,
    senders) bests: position, fitness, source of the best, and True where it is the own best
    (update_swarm_best)."""
    runs, n = own_fitness.shape
    position = np.empty((runs, n, 2))
    fitness = np.empty((runs, n))
    source = np.empty((runs, n), dtype=np.intp)
    mine = np.empty((runs, n), dtype=np.bool_)
    update_swarm_best(
        own_position,
        own_fitness,
        own_source,
        heard_position,
        heard_fitness,
        heard_source,
        links,
        np.ones((runs, n), dtype=np.bool_),
        position,
        fitness,
        source,
        mine,
    )
    return position, fitness, source, mine


@compiled
def update_swarm_best(
    own_position: FloatArray,
    own_fitness: FloatArray,
    own_source: IntArray,
    heard_position: FloatArray,
    heard_fitness: FloatArray,
    heard_source: IntArray,
    links: BoolArray,
    rows: BoolArray,
    position: FloatArray,
    fitness: FloatArray,
    source: IntArray,
    mine: BoolArray,
) -> None:
    """swarm_best of the particles where ``rows`` (runs, vehicles), written in place into
    ``position``, ``fitness``, ``source`` and ``mine`` (ties go to the own best; among the
    linked senders the first best wins, as argmax picks)."""
    runs, n = own_fitness.shape
    senders = links.shape[2]
    for r in range(runs):
        for i in range(n):
            if not rows[r, i]:
                continue
            other = -np.inf
            slot = 0
            for j in range(senders):
                if links[r, i, j] and heard_fitness[r, i, j] > other:
                    other = heard_fitness[r, i, j]
                    slot = j
            mine[r, i] = own_fitness[r, i] >= other
            if mine[r, i]:
                position[r, i, 0] = own_position[r, i, 0]
                position[r, i, 1] = own_position[r, i, 1]
                fitness[r, i] = own_fitness[r, i]
                source[r, i] = own_source[r, i]
            else:
                position[r, i, 0] = heard_position[r, i, slot, 0]
                position[r, i, 1] = heard_position[r, i, slot, 1]
                fitness[r, i] = other
                source[r, i] = heard_source[r, i, slot]


@compiled
def best_of_all_peers(
    own_position: FloatArray, own_fitness: FloatArray, own_source: IntArray
) -> tuple[FloatArray, FloatArray, IntArray, BoolArray]:
    """swarm_best when every vehicle hears every other's own best (message_delay 0, drop 0,
    links to every other vehicle: PSO, ARPSO), in (runs, vehicles) instead of (runs, vehicles,
    senders): every vehicle compares its own best with the run's first best. The vehicle that
    holds it keeps its own (a tie goes to the own best), as it would against the others'."""
    runs, n = own_fitness.shape
    chosen = np.empty((runs, n), dtype=np.intp)
    for r in range(runs):
        top = 0
        for j in range(1, n):
            if own_fitness[r, j] > own_fitness[r, top]:
                top = j
        for i in range(n):
            chosen[r, i] = i if own_fitness[r, i] >= own_fitness[r, top] else top
    return _own_bests(own_position, own_fitness, own_source, chosen)


@compiled
def best_of_linked_peers(
    own_position: FloatArray, own_fitness: FloatArray, own_source: IntArray, links: BoolArray
) -> tuple[FloatArray, FloatArray, IntArray, BoolArray]:
    """swarm_best when what every vehicle heard from sender j is j's own best (every message
    delivered; SPSO's informant ``links``): the run's vehicles are ordered once by fitness,
    highest first and the lower index first among equals, and each vehicle takes the first of
    its linked senders in that order: the first best among them, as argmax finds it, after a
    few links read instead of all of them."""
    runs, n = own_fitness.shape
    chosen = np.empty((runs, n), dtype=np.intp)
    order = np.empty(n, dtype=np.intp)
    for r in range(runs):
        for a in range(n):
            value = own_fitness[r, a]
            slot = a
            while slot > 0 and own_fitness[r, order[slot - 1]] < value:
                order[slot] = order[slot - 1]
                slot -= 1
            order[slot] = a
        for i in range(n):
            other = -np.inf
            sender = i
            for q in range(n):
                if links[r, i, order[q]]:
                    sender = order[q]
                    other = own_fitness[r, sender]
                    break
            chosen[r, i] = i if own_fitness[r, i] >= other else sender
    return _own_bests(own_position, own_fitness, own_source, chosen)


@compiled
def _own_bests(
    own_position: FloatArray, own_fitness: FloatArray, own_source: IntArray, chosen: IntArray
) -> tuple[FloatArray, FloatArray, IntArray, BoolArray]:
    """swarm_best's answer when each vehicle's best is vehicle ``chosen`` (runs, vehicles) of
    its run's own bests: position, fitness, source, and True where it chose itself (a sender
    is chosen only when strictly better, so never the vehicle itself)."""
    runs, n = own_fitness.shape
    position = np.empty((runs, n, 2))
    fitness = np.empty((runs, n))
    source = np.empty((runs, n), dtype=np.intp)
    mine = np.empty((runs, n), dtype=np.bool_)
    for r in range(runs):
        for i in range(n):
            best = chosen[r, i]
            mine[r, i] = best == i
            position[r, i, 0] = own_position[r, best, 0]
            position[r, i, 1] = own_position[r, best, 1]
            fitness[r, i] = own_fitness[r, best]
            source[r, i] = own_source[r, best]
    return position, fitness, source, mine


@compiled
def arpso_inertia(
    previous_best: FloatArray,
    best: FloatArray,
    current: FloatArray,
    heard_current: FloatArray,
    links: BoolArray,
    initial: float,
    speed_weight: float,
    aggregation_weight: float,
) -> FloatArray:
    """mdm_core.search.swarm_iteration.arpso_weights: per-particle A-RPSO inertia from the
    particle's own reading and its linked peers' (``heard_current`` (runs, vehicles, senders)),
    their mean summed in numpy's pairwise order."""
    runs, n = current.shape
    senders = links.shape[2]
    reads = np.empty(1 + senders)
    inertia = np.empty((runs, n))
    for r in range(runs):
        for i in range(n):
            reads[0] = top = current[r, i]
            count = 1
            for j in range(senders):
                value = 0.0
                if links[r, i, j]:
                    value = heard_current[r, i, j]
                    count += 1
                reads[1 + j] = value
                top = max(top, value)
            h = _ratio(previous_best[r, i], best[r, i])
            s = _ratio(_pairwise_sum(reads) / count, top)
            inertia[r, i] = initial - speed_weight * (1.0 - h) + aggregation_weight * s
    return inertia


@compiled
def _pairwise_sum(values: FloatArray) -> float:
    """values.sum() in numpy's order: runs of at most 128 summed by _block_sum, longer runs
    halved (on a multiple of 8) and the halves' sums added; walked with a stack, as numba's
    disk cache aborts on loading recursive functions."""
    if len(values) <= 128:
        return _block_sum(values, 0, len(values))
    start = np.zeros(128, dtype=np.intp)
    size = np.full(128, len(values))
    halved = np.zeros(128, dtype=np.bool_)
    sums = np.empty(128)
    top = 0
    done = 0
    while top >= 0:
        first, count = start[top], size[top]
        if count <= 128:
            sums[done] = _block_sum(values, first, count)
            done += 1
            top -= 1
        elif halved[top]:
            done -= 1
            sums[done - 1] += sums[done]
            top -= 1
        else:
            halved[top] = True
            half = count // 2
            half -= half % 8
            # The first half on top, so that its sum is below the second's.
            start[top + 1], size[top + 1], halved[top + 1] = first + half, count - half, False
            start[top + 2], size[top + 2], halved[top + 2] = first, half, False
            top += 2
    return float(sums[0])


@compiled
def _block_sum(values: FloatArray, first: int, count: int) -> float:
    """values[first:first + count].sum() for count <= 128 in numpy's order: in sequence below 8
    values, else 8 interleaved accumulators added pairwise, then the remainder in sequence
    (read by index: slices of ``values`` cost more than the sums)."""
    if count < 8:
        total = 0.0
        for i in range(first, first + count):
            total += values[i]
        return total
    a0, a1, a2, a3 = values[first], values[first + 1], values[first + 2], values[first + 3]
    a4, a5, a6, a7 = values[first + 4], values[first + 5], values[first + 6], values[first + 7]
    i = first + 8
    end = first + count - count % 8
    while i < end:
        a0 += values[i]
        a1 += values[i + 1]
        a2 += values[i + 2]
        a3 += values[i + 3]
        a4 += values[i + 4]
        a5 += values[i + 5]
        a6 += values[i + 6]
        a7 += values[i + 7]
        i += 8
    total = ((a0 + a1) + (a2 + a3)) + ((a4 + a5) + (a6 + a7))
    for k in range(end, first + count):
        total += values[k]
    return float(total)


@compiled
def _ratio(a: float, b: float) -> float:
    """min / max of two fitnesses, 1 when both are 0 (mdm_core.search.pso.arpso_inertia)."""
    hi = max(a, b)
    return min(a, b) / hi if hi > 0 else 1.0


@compiled
def pso_steps(
    step: FloatArray,
    position: FloatArray,
    own_position: FloatArray,
    own_fitness: FloatArray,
    social_position: FloatArray,
    social_fitness: FloatArray,
    inertia: FloatArray,
    c1: float,
    c2: float,
    uniform: FloatArray,
    max_step: float,
    constant_speed: bool,
) -> FloatArray:
    """mdm_core.search.pso.next_step for PSO and ARPSO: pso_step (a best of fitness 0 pulls
    nowhere) with per-particle ``inertia`` (runs, vehicles), then clamp; ``uniform`` (2, runs,
    vehicles, 2): its r1, then its r2."""
    runs, n, _ = position.shape
    r1 = uniform[0]
    r2 = uniform[1]
    raw = np.empty((runs, n, 2))
    for r in range(runs):
        for i in range(n):
            w = inertia[r, i]
            for a in range(2):
                x = position[r, i, a]
                personal, social = _pulls(
                    x,
                    own_position[r, i, a],
                    own_fitness[r, i],
                    social_position[r, i, a],
                    social_fitness[r, i],
                )
                raw[r, i, a] = (
                    w * step[r, i, a]
                    + c1 * r1[r, i, a] * (personal - x)
                    + c2 * r2[r, i, a] * (social - x)
                )
    clamp(raw, max_step, constant_speed)
    return raw


@compiled
def spso_steps(
    step: FloatArray,
    position: FloatArray,
    own_position: FloatArray,
    own_fitness: FloatArray,
    local_position: FloatArray,
    local_fitness: FloatArray,
    own_is_local: BoolArray,
    inertia: float,
    acceleration: float,
    direction: FloatArray,
    uniform: FloatArray,
    max_step: float,
    constant_speed: bool,
) -> FloatArray:
    """mdm_core.search.pso.next_step for SPSO: spso_step from its draws, the standard normal
    ``direction`` (runs, vehicles, 2), then the radii's ``uniform`` (runs, vehicles); then
    clamp."""
    runs, n, _ = position.shape
    c = acceleration
    raw = np.empty((runs, n, 2))
    centre = np.empty(2)
    for r in range(runs):
        for i in range(n):
            for a in range(2):
                x = position[r, i, a]
                p, g = _pulls(
                    x,
                    own_position[r, i, a],
                    own_fitness[r, i],
                    local_position[r, i, a],
                    local_fitness[r, i],
                )
                if own_is_local[r, i]:
                    centre[a] = x + c * (p - x) / 2.0
                else:
                    centre[a] = x + c * (p + g - 2.0 * x) / 3.0
            radius = _length(centre[0] - position[r, i, 0], centre[1] - position[r, i, 1])
            norm = _length(direction[r, i, 0], direction[r, i, 1])
            if not norm > 0:
                norm = 1.0
            reach = radius * math.sqrt(uniform[r, i])
            for a in range(2):
                sample = centre[a] + direction[r, i, a] / norm * reach
                raw[r, i, a] = inertia * step[r, i, a] + sample - position[r, i, a]
    clamp(raw, max_step, constant_speed)
    return raw


@compiled
def _pulls(
    x: float, own: float, own_fitness: float, social: float, social_fitness: float
) -> tuple[float, float]:
    """One coordinate of the personal and social bests a particle is pulled to: itself for a
    best of fitness 0, its personal best for a social best of fitness 0 (next_step)."""
    personal = own if own_fitness > 0 else x
    return personal, social if social_fitness > 0 else personal


@compiled
def clamp(step: FloatArray, max_step: float, constant_speed: bool) -> None:
    """mdm_core.search.pso.clamp in place on steps (runs, vehicles, 2)."""
    runs, n, _ = step.shape
    for r in range(runs):
        for i in range(n):
            size = _length(step[r, i, 0], step[r, i, 1])
            too_long = size > 0 if constant_speed else size > max_step
            if too_long:
                scaled = max_step / size
                step[r, i, 0] *= scaled
                step[r, i, 1] *= scaled


@compiled
def fly(
    position: FloatArray,
    swarm_move: FloatArray,
    follow: BoolArray,
    waypoint: FloatArray,
    distance: float,
    area: FloatArray,
) -> tuple[FloatArray, FloatArray, BoolArray, float]:
    """One interval's flight: followers take ``swarm_move``, the others head for their
    waypoint, at most ``distance`` (swarm_iteration.choose_move), clipped to the area.
    Returns the new positions, the steps flown, which explorers reached their waypoint and the
    largest absolute coordinate of a step."""
    runs, n, _ = position.shape
    new_position = np.empty((runs, n, 2))
    step = np.empty((runs, n, 2))
    reached = np.zeros((runs, n), dtype=np.bool_)
    longest = 0.0
    for r in range(runs):
        for i in range(n):
            scale = 1.0
            if not follow[r, i]:
                gap = _length(
                    waypoint[r, i, 0] - position[r, i, 0], waypoint[r, i, 1] - position[r, i, 1]
                )
                scale = min(1.0, distance / max(gap, 1e-12))
            for a in range(2):
                x = position[r, i, a]
                move = swarm_move[r, i, a] if follow[r, i] else (waypoint[r, i, a] - x) * scale
                moved = min(max(x + move, 0.0), area[a])
                new_position[r, i, a] = moved
                step[r, i, a] = moved - x
                longest = max(longest, abs(moved - x))
            if not follow[r, i]:
                left = _length(
                    waypoint[r, i, 0] - new_position[r, i, 0],
                    waypoint[r, i, 1] - new_position[r, i, 1],
                )
                reached[r, i] = left <= 1e-6
    return new_position, step, reached, longest


@compiled
def informants(keys: FloatArray, k: int) -> BoolArray:
    """mdm_core.search.pso.random_informants from its uniform ``keys`` (runs, n, n), whose
    diagonal is set to inf in place (_link_row)."""
    runs, n, _ = keys.shape
    links = np.empty((runs, n, n), dtype=np.bool_)
    for r in range(runs):
        for i in range(n):
            _link_row(keys, r, i, k, links)
    return links


@compiled
def relink(keys: FloatArray, stuck: BoolArray, k: int, links: BoolArray) -> None:
    """SPSO's adaptive random topology (mdm_core.search.swarm_iteration.refresh_informants)
    in place: the rows of ``links`` of the ``stuck`` (runs, n) particles become those of
    informants(keys, k) (the rest of ``keys`` is not read)."""
    runs, n = stuck.shape
    for r in range(runs):
        for i in range(n):
            if stuck[r, i]:
                _link_row(keys, r, i, k, links)


@compiled
def _link_row(keys: FloatArray, r: int, i: int, k: int, links: BoolArray) -> None:
    """Row (r, i) of random_informants from its keys (runs, n, n), keys[r, i, i] set to inf in
    place: links[r, i] True for the k particles other than i with the smallest keys, those with
    fewer than k keys below theirs (keys <= the k-th smallest, as numpy's partition finds it)."""
    n = keys.shape[2]
    keys[r, i, i] = np.inf
    k = min(k, n - 1)
    for j in range(n):
        key = keys[r, i, j]
        below = 0
        for other in range(n):
            below += keys[r, i, other] < key
        links[r, i, j] = below < k


@compiled
def _length(x: float, y: float) -> float:
    """|(x, y)| as mdm_core.search.planar.length computes it."""
    return math.sqrt(x * x + y * y)
