"""The lawnmower teams stepped every ``dt`` in plain Python: the reference the compiled engine
(mdm_montecarlo.kernels.lawnmower_kernel) is tested against.

Each vehicle spends a distance budget of speed x dt per step along its course (a waypoint
reached within a step hands the rest of the step to the next one, so the path is the engine's
and only the sensor reads are quantised), then reads its sensor at the step's end position
against the targets' positions at that time (TargetTracks.positions): a target counts from the
first step end at which it is strictly inside the disc. The rules are those of the engine's
docstring, written again here step by step: LM1 confirms what passes under its confirmation
sensor; LM2 detects on the lanes, flies the spiral round the point of detection with the
confirmation sensor until the detected target is confirmed or the spiral ends, then flies back
to the point where it left its lane.
"""

from __future__ import annotations

import math

import numpy as np

from mdm_core.search.lawnmower import Plan
from mdm_core.search.lawnmower_profile import search_hold, search_spiral, team_plan
from mdm_core.world import Scenario
from mdm_montecarlo.engines.engine import block_rngs
from mdm_montecarlo.kernels.compiled_tracks import compiled_tracks
from mdm_profiles import MissionProfile


def stepped_lawnmower(
    profile: MissionProfile, seed: int, block: int, n_runs: int, dt: float
) -> np.ndarray:
    """Each run's team first-confirmation times (runs, targets), inf where never, stepped."""
    scenario = Scenario.from_profile(profile)
    rng_targets, rng_start, _ = block_rngs(seed, block)
    n_vehicles = profile.fleet.vehicles
    cap = max(profile.mission.ts_cap, profile.mission.duration)
    tracks = compiled_tracks(scenario, n_runs, rng_targets, cap)
    start = scenario.start_positions(n_runs, n_vehicles, profile.fleet.start, rng_start)
    times = _step_ends(dt, cap)
    team = np.full((n_runs, scenario.targets.count), np.inf)
    for r in range(n_runs):
        plan = team_plan(profile, start[r])
        # Every step end's target positions at once, shared by the run's vehicles: the same
        # numbers as one call per step (elementwise arithmetic), without a call per step.
        where = tracks.positions(np.full(len(times), r), times)
        for i in range(n_vehicles):
            first = _fly_one(profile, scenario, times, where, start[r, i], plan, i, dt)
            team[r] = np.minimum(team[r], first)
    return team


def _step_ends(dt: float, cap: float) -> np.ndarray:
    """The times at which the steps end, summed step by step as the vehicles' clock is."""
    ends: list[float] = []
    t = 0.0
    while t < cap - 1e-9:
        t += dt
        ends.append(t)
    return np.array(ends)


def _fly_one(
    profile: MissionProfile,
    scenario: Scenario,
    times: np.ndarray,
    where_at: np.ndarray,
    start: np.ndarray,
    plan: Plan,
    vehicle: int,
    dt: float,
) -> np.ndarray:
    """One vehicle's first-confirmation times (targets,); ``where_at[j]``: the targets'
    positions (m, 2) at step end ``times[j]``."""
    two = profile.policy.kind == "lm2"
    sweep = plan.waypoints[vehicle]
    spiral = search_spiral(profile)
    hold = search_hold(profile)
    r_detect = scenario.sensors[0].radius
    r_confirm = scenario.confirmation.radius
    size = scenario.area.size
    real = ~scenario.targets.false_mask
    appear = scenario.targets.appear_times
    m = scenario.targets.count
    speed = profile.fleet.speed
    first = np.full(m, np.inf)
    hold_until = np.zeros(m)
    resolved = np.zeros(m, dtype=bool)
    pos = np.asarray(start, dtype=float).copy()
    mode, k, step, s = "sweep", 0, 1, 0
    centre = heading = back = np.zeros(2)
    sought = -1

    def goal() -> np.ndarray:
        if mode == "sweep":
            return np.asarray(sweep[k])
        if mode == "return":
            return back
        ox, oy = spiral[s]
        hx, hy = heading
        point = centre + np.array([ox * hx - oy * hy, ox * hy + oy * hx])
        return np.asarray(np.clip(point, 0.0, size))

    for j, t in enumerate(times.tolist()):
        budget = speed * dt
        direction = np.zeros(2)
        while budget > 0:
            target = goal()
            gap = float(np.hypot(*(target - pos)))
            if gap > 1e-9:
                direction = (target - pos) / gap
            if gap > budget:
                pos = pos + direction * budget
                break
            pos = target.copy()
            budget -= gap
            if mode == "sweep":
                k += step
                if k == len(sweep) or k < 0:
                    step = -step
                    k += 2 * step
                    hold_until[np.isinf(hold_until)] = 0.0
            elif mode == "return":
                mode = "sweep"
            else:
                s += 1
                if s == len(spiral):
                    hold_until[sought] = t + hold if hold >= 0 else np.inf
                    mode = "return"
        near = np.hypot(*(where_at[j] - pos).T)
        present = appear <= t
        if not two or mode == "search":
            hit = real & present & np.isinf(first) & (near < r_confirm)
            first[hit] = t
            resolved |= hit
            if mode == "search" and resolved[sought]:
                mode = "return"
        else:
            hit = present & ~resolved & (hold_until <= t) & (near < r_detect)
            if hit.any():
                sought = int(np.flatnonzero(hit)[np.argmin(near[hit] - r_detect)])
                if mode == "sweep":
                    back = pos.copy()
                mode, s, centre = "search", 0, pos.copy()
                heading = direction if math.hypot(*direction) > 0 else np.array([1.0, 0.0])
        if t >= profile.mission.duration and np.isfinite(first[real]).all():
            break
    return first
