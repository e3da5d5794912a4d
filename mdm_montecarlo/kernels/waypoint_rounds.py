"""The waypoint swarm's steps with arrivals, compiled (numba) into one loop: a block runs in
one call.

Each round jumps to the next step at which particles arrive at their waypoints (their legs were
solved when they started: mdm_montecarlo.kernels.waypoint_legs), reads their sensor there, forgets the
bests of confirmed targets where the profile says so, runs the arrivals' iteration (``arrive``)
and starts their next legs. Called from Python, a round was some forty numpy calls on the
arrivals' few hundred particles, about half of the rows' CPU time. The random numbers come
from the same numpy Generator in the same order and shapes (numba draws the numbers numpy
draws), and every kernel is the one the Python round called, so the results are the same to
the bit (tests/montecarlo/test_waypoint_legs.py against the swarm stepped every interval).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled
from mdm_montecarlo.kernels import swarm_kernels as kernels
from mdm_montecarlo.kernels import waypoint_kernels
from mdm_montecarlo.kernels.compiled_waypoints import next_waypoints
from mdm_montecarlo.kernels.waypoint_legs import forget_confirmed, read_arrivals, walk_legs

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]

PSO, SPSO, ARPSO = range(3)
VARIANTS = {"pso": PSO, "spso": SPSO, "arpso": ARPSO}

RULE_COLUMNS = (
    "inertia",
    "cognitive",
    "social",
    "spso_inertia",
    "spso_acceleration",
    "max_step",
    "arpso_initial_inertia",
    "arpso_speed_weight",
    "arpso_aggregation_weight",
)
"""The columns of ``rules``: the swarm's constants (SwarmConfig's fields) as arrive reads them."""
(
    INERTIA,
    COGNITIVE,
    SOCIAL,
    SPSO_INERTIA,
    SPSO_ACCELERATION,
    MAX_STEP,
    ARPSO_INITIAL,
    ARPSO_SPEED,
    ARPSO_AGGREGATION,
) = range(len(RULE_COLUMNS))


@compiled
def arrive(
    variant: int,
    rules: FloatArray,
    informants: int,
    run: IntArray,
    lane: IntArray,
    own_position: FloatArray,
    own_fitness: FloatArray,
    own_source: IntArray,
    position: FloatArray,
    reading: FloatArray,
    source: IntArray,
    current: FloatArray,
    velocity: FloatArray,
    waypoint: FloatArray,
    links: BoolArray,
    local_fitness: FloatArray,
    table: FloatArray,
    bounds: FloatArray,
    rule: int,
    from_anchor: bool,
    confine: bool,
    area: FloatArray,
    rng: np.random.Generator,
) -> int:
    """The iteration of every particle that reached its waypoint (``run``, ``lane``: the
    arrivals in run, then vehicle order): its reading into its personal best, then its next
    velocity and waypoint, in place. Returns how many of them steer by another vehicle's best.

    The swarm bests, inertias and steps are computed for the arrivals alone (the kernels'
    per-particle rules on them as (arrivals, 1) particles; the swarm bests over the runs they
    belong to). The random numbers are drawn for them alone: PSO/ARPSO r1 then r2, (2,
    arrivals, 1, 2); SPSO the normals (arrivals, 1, 2), the radii's uniforms (arrivals, 1),
    then the informant keys (stuck, vehicles) of those stuck; then the explorers' level-1
    waypoints (SearchPolicy.start's draw, compiled_waypoints.next_waypoints)."""
    count = run.shape[0]
    n = own_fitness.shape[1]
    previous = waypoint_kernels.take_readings(
        run, lane, position, reading, source, current, own_position, own_fitness, own_source
    )
    # The runs with arrivals (``run`` is sorted) and each arrival's row among them.
    slot = np.empty(count, dtype=np.intp)
    hits = 0
    for a in range(count):
        if a == 0 or run[a] != run[a - 1]:
            hits += 1
        slot[a] = hits - 1
    hit_runs = np.empty(hits, dtype=np.intp)
    for a in range(count):
        hit_runs[slot[a]] = run[a]
    if variant == SPSO:
        found = kernels.best_of_linked_peers(
            own_position[hit_runs], own_fitness[hit_runs], own_source[hit_runs], links[hit_runs]
        )
    else:
        found = kernels.best_of_all_peers(
            own_position[hit_runs], own_fitness[hit_runs], own_source[hit_runs]
        )
    # The arrivals as (arrivals, 1) particles.
    social_position = np.empty((count, 1, 2))
    social_fitness = np.empty((count, 1))
    mine = np.empty((count, 1), dtype=np.bool_)
    step = np.empty((count, 1, 2))
    here = np.empty((count, 1, 2))
    mine_position = np.empty((count, 1, 2))
    mine_fitness = np.empty((count, 1))
    for a in range(count):
        r, i, s = run[a], lane[a], slot[a]
        social_fitness[a, 0] = found[1][s, i]
        mine[a, 0] = found[3][s, i]
        mine_fitness[a, 0] = own_fitness[r, i]
        for k in range(2):
            social_position[a, 0, k] = found[0][s, i, k]
            step[a, 0, k] = velocity[r, i, k]
            here[a, 0, k] = position[r, i, k]
            mine_position[a, 0, k] = own_position[r, i, k]
    if variant == SPSO:
        normal = rng.standard_normal((count, 1, 2))
        uniform = rng.random((count, 1))
        move = kernels.spso_steps(
            step,
            here,
            mine_position,
            mine_fitness,
            social_position,
            social_fitness,
            mine,
            rules[SPSO_INERTIA],
            rules[SPSO_ACCELERATION],
            normal,
            uniform,
            rules[MAX_STEP],
            False,
        )
        stuck = np.zeros(own_fitness.shape, dtype=np.bool_)
        stuck_count = 0
        for a in range(count):
            r, i = run[a], lane[a]
            if social_fitness[a, 0] <= local_fitness[r, i]:
                stuck[r, i] = True
                stuck_count += 1
            local_fitness[r, i] = social_fitness[a, 0]
        if stuck_count > 0:
            # relink reads the keys of the stuck particles' rows only.
            drawn = rng.random((stuck_count, n))
            keys = np.empty(links.shape)
            row = 0
            for a in range(count):
                r, i = run[a], lane[a]
                if stuck[r, i]:
                    keys[r, i] = drawn[row]
                    row += 1
            kernels.relink(keys, stuck, informants, links)
    else:
        inertia = np.full((count, 1), rules[INERTIA])
        if variant == ARPSO:
            heard = np.empty((count, 1, n))
            linked = np.empty((count, 1, n), dtype=np.bool_)
            now = np.empty((count, 1))
            before = np.empty((count, 1))
            for a in range(count):
                r, i = run[a], lane[a]
                now[a, 0] = current[r, i]
                before[a, 0] = previous[a]
                for j in range(n):
                    heard[a, 0, j] = current[r, j]
                    linked[a, 0, j] = links[r, i, j]
            inertia = kernels.arpso_inertia(
                before,
                mine_fitness,
                now,
                heard,
                linked,
                rules[ARPSO_INITIAL],
                rules[ARPSO_SPEED],
                rules[ARPSO_AGGREGATION],
            )
        uniform = rng.random((2, count, 1, 2))
        move = kernels.pso_steps(
            step,
            here,
            mine_position,
            mine_fitness,
            social_position,
            social_fitness,
            inertia,
            rules[COGNITIVE],
            rules[SOCIAL],
            uniform,
            rules[MAX_STEP],
            False,
        )
    follow = np.empty(count, dtype=np.bool_)
    lost = 0
    followed = 0
    for a in range(count):
        follow[a] = social_fitness[a, 0] > 0
        lost += not follow[a]
        followed += follow[a] and not mine[a, 0]
    if lost > 0:
        # SearchPolicy.start from where they are: level 1, anchored there.
        start = np.empty((lost, 2))
        k = 0
        for a in range(count):
            if not follow[a]:
                start[k, 0] = position[run[a], lane[a], 0]
                start[k, 1] = position[run[a], lane[a], 1]
                k += 1
        drawn_waypoints = next_waypoints(
            table,
            np.zeros(lost, dtype=np.intp),
            start.copy(),
            start,
            bounds,
            rule,
            from_anchor,
            confine,
            rng,
        )
        k = 0
        for a in range(count):
            if not follow[a]:
                waypoint[run[a], lane[a], 0] = drawn_waypoints[k, 0]
                waypoint[run[a], lane[a], 1] = drawn_waypoints[k, 1]
                k += 1
    moves = np.empty((count, 2))
    for a in range(count):
        moves[a, 0] = move[a, 0, 0]
        moves[a, 1] = move[a, 0, 1]
    waypoint_kernels.steer(run, lane, follow, position, moves, area, waypoint, velocity)
    return followed


@compiled
def fly_waypoints(
    variant: int,
    rules: FloatArray,
    informants: int,
    times: FloatArray,
    dt: float,
    distance: float,
    past_duration: int,
    position: FloatArray,
    waypoint: FloatArray,
    velocity: FloatArray,
    own_position: FloatArray,
    own_fitness: FloatArray,
    own_source: IntArray,
    reading: FloatArray,
    source: IntArray,
    current: FloatArray,
    links: BoolArray,
    local_fitness: FloatArray,
    seg_start: FloatArray,
    seg_velocity: FloatArray,
    grid_dt: float,
    moving: bool,
    top_speed: float,
    appear: FloatArray,
    real: BoolArray,
    confirm_radius: float,
    signal_radius: float,
    near: float,
    unread_known: bool,
    forget: bool,
    table: FloatArray,
    bounds: FloatArray,
    rule: int,
    from_anchor: bool,
    confine: bool,
    area: FloatArray,
    known_step: IntArray,
    conf_time: FloatArray,
    conf_step: IntArray,
    rng: np.random.Generator,
) -> tuple[int, int, int]:
    """The whole block: every particle's first leg from step 0, then round after round to the
    next step with arrivals, until the time-stepped loop would stop (the first step from
    ``past_duration`` on by which every run has confirmed every real target, or the last
    step). The particles' arrays are (runs, vehicles, ...) and updated in place, as are
    ``known_step``, ``conf_time`` and ``conf_step`` (waypoint_legs.walk_legs). Returns the last
    step, the iterations (arrivals) and how many of them followed another vehicle's best."""
    runs, n_vehicles = own_fitness.shape
    n = runs * n_vehicles
    last = times.shape[0] - 1
    flat = position.reshape(n, 2)
    arrival_step = np.empty(n, dtype=np.intp)
    arrival = np.empty((n, 2))
    # Every particle's first leg from step 0, then the legs of each step's arrivals.
    starting = np.arange(n)
    begin = 0
    iterations = 0
    followed = 0
    while True:
        walk_legs(
            starting,
            flat,
            waypoint.reshape(n, 2),
            begin,
            times,
            dt,
            distance,
            area,
            n_vehicles,
            seg_start,
            seg_velocity,
            grid_dt,
            moving,
            top_speed,
            appear,
            real,
            confirm_radius,
            known_step,
            conf_time,
            conf_step,
            arrival_step,
            arrival,
        )
        due = arrival_step.min()
        all_known = 0
        for r in range(runs):
            for j in range(real.shape[0]):
                if real[j]:
                    all_known = max(all_known, known_step[r, j])
        end = min(max(past_duration, all_known), last)
        if end < due:
            return end, iterations, followed
        # Every confirmation by step ``due`` is known: later legs start after it.
        arrived = np.flatnonzero(arrival_step == due)
        for p in arrived:
            flat[p, 0] = arrival[p, 0]
            flat[p, 1] = arrival[p, 1]
        t = times[due]
        read_arrivals(
            arrived,
            flat,
            seg_start,
            seg_velocity,
            grid_dt,
            moving,
            appear,
            t,
            signal_radius,
            near,
            known_step,
            due,
            unread_known,
            n_vehicles,
            reading.reshape(n),
            source.reshape(n),
        )
        if forget:
            forget_confirmed(
                own_fitness.reshape(n), own_source.reshape(n), known_step, due, n_vehicles
            )
        iterations += arrived.size
        followed += arrive(
            variant,
            rules,
            informants,
            arrived // n_vehicles,
            arrived % n_vehicles,
            own_position,
            own_fitness,
            own_source,
            position,
            reading,
            source,
            current,
            velocity,
            waypoint,
            links,
            local_fitness,
            table,
            bounds,
            rule,
            from_anchor,
            confine,
            area,
            rng,
        )
        if end == due:
            # The stepped loop stops after this step's arrivals: their next legs are not flown.
            return end, iterations, followed
        starting = arrived
        begin = due
