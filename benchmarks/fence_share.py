"""Share of level-1 search time within 30 m of a field fence, batch: waypoints clamped onto the
inset fence by the companion (`policy.out_of_area: reflect` on the search area, no fence in
the policy) against waypoints redrawn inside it (`redraw`).

Each vehicle starts where the companion starts it (the engine's periphery start point clamped
into the inset fence) and flies straight legs at ``fleet.speed`` (as the engine does) to each
waypoint as the companion flies it (clamped into the inset fence, reached there); its position
is sampled every second of a ``mission.duration`` search. Level 1 only (no targets: a level-2
excursion lasts at most 363 s and stays within r_1 of a detection, so this is the part of the
search the fence rule changes). Usage:

    .venv/bin/python benchmarks/fence_share.py [--runs 200] [--seed 1] [--profile field-duebendorf]
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from companion.fence_from_profile import fence_for, guidance_fence
from mdm_core.search import Observation, SearchPolicy
from mdm_core.search.from_profile import policy_config
from mdm_core.world import Scenario
from mdm_ground.fleet.flight_checks import NEAR_FENCE_M
from mdm_profiles import builtin_profile


def _share(profile_name: str, fenced: bool, runs: int, seed: int) -> tuple[float, float]:
    """(share of samples within NEAR_FENCE_M of the fence, share of drawn waypoints outside
    the inset fence)."""
    profile = builtin_profile(profile_name)
    config = policy_config(profile)
    config = dataclasses.replace(config, levels=config.levels[:1])
    if not fenced:  # the area's own rule; the companion clamps onto the fence
        config = dataclasses.replace(config, out_of_area="reflect", fence=())
    policy = SearchPolicy(config)
    fence, inner = fence_for(profile), guidance_fence(profile)
    speed, duration = profile.fleet.speed, profile.mission.duration
    rng = np.random.default_rng(seed)
    scenario = Scenario.from_profile(profile)
    near = samples = drawn = clamped = 0
    for _ in range(runs):
        starts = scenario.start_positions(1, profile.fleet.vehicles, profile.fleet.start, rng)[0]
        for start in starts:
            here = inner.clamp(start)
            state = policy.start(here[None, :], np.zeros(1), rng)
            t = 0.0
            while t < duration:
                goal = inner.clamp(state.waypoint[0])
                drawn += 1
                clamped += int(not np.array_equal(goal, state.waypoint[0]))
                leg = float(np.hypot(*(goal - here)))
                steps = max(1, int(leg / speed))
                for k in range(1, steps + 1):
                    if t + k > duration:
                        break
                    p = here + (goal - here) * min(1.0, k * speed / max(leg, 1e-9))
                    near += fence.distance(float(p[0]), float(p[1])) <= NEAR_FENCE_M
                    samples += 1
                t += max(leg / speed, 1.0)
                here = goal
                obs = Observation(
                    time=np.array([t]),
                    position=here[None, :],
                    reached=np.array([True]),
                    contacts=np.zeros((1, 1), dtype=bool),
                    contact_positions=np.zeros((1, 1, 2)),
                )
                policy.step(state, np.array([0]), obs, rng)
    return near / samples, clamped / drawn


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="field-duebendorf", help="a built-in field profile")
    parser.add_argument("--runs", type=int, default=200)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    for fenced, name in ((False, "clamped onto the inset fence"), (True, "redrawn inside it")):
        near, clamped = _share(args.profile, fenced, args.runs, args.seed)
        print(
            f"{name}: {near:.1%} of search samples within {NEAR_FENCE_M:g} m of the fence; "
            f"{clamped:.1%} of waypoints clamped"
        )


if __name__ == "__main__":
    main()
