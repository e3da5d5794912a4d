"""The waypoint swarm stepped the plain way, every particle every update interval: the
reference that mdm_montecarlo.engines.waypoint_swarm's leg-by-leg engine must match to the bit
(tests/montecarlo/test_waypoint_legs.py). It is the engine as it was before the legs were
solved in one piece (swarm_kernels.fly, SwarmSensors.sense and confirm on every step)."""

from __future__ import annotations

import numpy as np

from mdm_core.search.from_profile import policy_config, signal_radius
from mdm_core.search.pso import Best, SwarmConfig
from mdm_core.search.swarm_iteration import explore
from mdm_core.world import Scenario
from mdm_montecarlo.engines.engine import BlockResult, block_rngs
from mdm_montecarlo.engines.swarm_sensors import SwarmSensors
from mdm_montecarlo.engines.waypoint_swarm import rules_of, swarm_rules
from mdm_montecarlo.kernels import swarm_kernels as kernels
from mdm_montecarlo.kernels.compiled_step import CompiledPolicy
from mdm_montecarlo.kernels.compiled_tracks import compiled_tracks
from mdm_montecarlo.kernels.compiled_waypoints import RULES
from mdm_montecarlo.kernels.waypoint_rounds import VARIANTS, arrive
from mdm_profiles import MissionProfile


def stepped_block(profile: MissionProfile, seed: int, block: int, n_runs: int) -> BlockResult:
    """run_waypoint_swarm_block, every particle flown, sensed and confirmed on every step."""
    scenario = Scenario.from_profile(profile)
    spec = profile.policy.swarm
    config = swarm_rules(profile)
    explorer = CompiledPolicy(policy_config(profile))
    rng_targets, rng_start, rng = block_rngs(seed, block)
    n_vehicles = profile.fleet.vehicles
    shape = (n_runs, n_vehicles)
    n = n_runs * n_vehicles
    dt = spec.update_interval
    stop = max(profile.mission.ts_cap, profile.mission.duration)
    targets = scenario.targets
    real = ~targets.false_mask
    sensors = SwarmSensors(
        tracks=compiled_tracks(scenario, n_runs, rng_targets, stop),
        runs=np.arange(n_runs),
        real=real,
        appear=targets.appear_times,
        confirm_radius=scenario.confirmation.radius,
        signal_radius=signal_radius(profile),
        dt=dt,
    )
    position = scenario.start_positions(n_runs, n_vehicles, profile.fleet.start, rng_start)
    area = np.asarray(scenario.area.size, dtype=float)
    first = np.full((*shape, targets.count), np.inf)
    known = np.zeros((*shape, targets.count), dtype=bool)
    nothing = np.zeros_like(known)
    unread = nothing if spec.read_confirmed else known
    forget_by = known if spec.after_confirmation == "forget" else nothing
    own = Best(position.copy(), np.zeros(shape), np.full(shape, -1, dtype=np.intp))
    current = np.zeros(shape)
    reading = np.zeros(shape)
    source = np.full(shape, -1, dtype=np.intp)
    nearest = np.empty(shape)
    links = np.broadcast_to(~np.eye(n_vehicles, dtype=bool), (*shape, n_vehicles)).copy()
    if config.variant == "spso":
        links = kernels.informants(rng.random((n_runs, n_vehicles, n_vehicles)), spec.informants)
    local_fitness = np.zeros(shape)
    waypoint = explore(explorer, position.reshape(n, 2), rng).reshape(*shape, 2)
    velocity = waypoint - position
    no_move = np.zeros((*shape, 2))
    no_follow = np.zeros(shape, dtype=bool)
    targets_now = sensors.motion(0.0)
    sensors.sense(targets_now, position, unread, no_follow, reading, source, nearest)
    t = 0.0
    iterations = 0
    followed = 0
    while t < stop - 1e-9:
        new_position, step, reached, longest = kernels.fly(
            position, no_move, no_follow, waypoint, profile.fleet.speed * dt, area
        )
        run, index = sensors.confirm(targets_now, position, nearest, step, longest, first, known)
        known[run, :, index] = True
        position = new_position
        t += dt
        targets_now = sensors.motion(t)
        sensors.sense(targets_now, position, unread, reached, reading, source, nearest)
        kernels.forget_known(own.fitness, own.source, forget_by)
        if reached.any():
            iterations += int(np.count_nonzero(reached))
            followed += arrive_reached(
                config,
                spec.informants,
                explorer,
                own,
                reached,
                position,
                reading,
                source,
                current,
                velocity,
                waypoint,
                links,
                local_fitness,
                area,
                rng,
            )
        if t >= profile.mission.duration and bool(np.isfinite(first.min(axis=1)[:, real]).all()):
            break
    return BlockResult(block, first, iterations, float(t * n), followed)


def arrive_reached(
    config: SwarmConfig,
    informants: int,
    explorer: CompiledPolicy,
    own: Best,
    reached: np.ndarray,
    position: np.ndarray,
    reading: np.ndarray,
    source: np.ndarray,
    current: np.ndarray,
    velocity: np.ndarray,
    waypoint: np.ndarray,
    links: np.ndarray,
    local_fitness: np.ndarray,
    area: np.ndarray,
    rng: np.random.Generator,
) -> int:
    """waypoint_rounds.arrive for the particles where ``reached`` (runs, vehicles)."""
    run, lane = np.nonzero(reached)
    assert explorer.table is not None
    return int(
        arrive(
            VARIANTS[config.variant],
            rules_of(config),
            informants,
            run,
            lane,
            own.position,
            own.fitness,
            own.source,
            position,
            reading,
            source,
            current,
            velocity,
            waypoint,
            links,
            local_fitness,
            explorer.table,
            explorer.area,
            RULES[explorer.config.out_of_area],
            explorer.config.waypoint_origin == "anchor",
            explorer.config.confine_to_detection,
            area,
            rng,
        )
    )
