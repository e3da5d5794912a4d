"""The waypoint swarm solved leg by leg (mdm_montecarlo.kernels.waypoint_legs) against the same swarm
stepped every interval (stepped_waypoint_swarm): every vehicle's first confirmation times, the
iterations, the followed bests and the simulated time equal to the bit, for every scenario,
swarm, reading and the edge cases of the stepped loop (its end before the last step, an
interval that does not add up exactly, false targets)."""

from __future__ import annotations

import numpy as np
import pytest

from mdm_montecarlo.engines.waypoint_swarm import run_waypoint_swarm_block
from mdm_montecarlo.study.cases import Case
from mdm_profiles import MissionProfile
from mdm_profiles.overrides import apply_overrides
from tests.montecarlo.stepped_waypoint_swarm import stepped_block

TEXT = (
    "policy.swarm.iteration=waypoint",
    "policy.swarm.signal_sensor=confirmation",
    "policy.swarm.after_confirmation=keep",
    "policy.swarm.read_confirmed=true",
)
FORGETS = (
    "policy.swarm.iteration=waypoint",
    "policy.swarm.signal_sensor=confirmation",
    "policy.swarm.after_confirmation=forget",
    "policy.swarm.read_confirmed=false",
)
DETECTION = ("policy.swarm.iteration=waypoint", "policy.swarm.signal_sensor=detection")


def _profile(scenario: str, method: str, *settings: str) -> MissionProfile:
    return apply_overrides(Case(scenario, method, 20.0, 12, 0).profile(), list(settings))


def _same(profile: MissionProfile, seed: int, runs: int) -> None:
    legs = run_waypoint_swarm_block(profile, seed, 1, runs)
    stepped = stepped_block(profile, seed, 1, runs)
    assert np.array_equal(legs.per_vehicle, stepped.per_vehicle)
    assert (legs.events, legs.followed, legs.sim_seconds) == (
        stepped.events,
        stepped.followed,
        stepped.sim_seconds,
    )
    # Not a vacuous match: targets were confirmed and particles iterated.
    assert np.isfinite(stepped.per_vehicle).any()
    assert stepped.events > runs * profile.fleet.vehicles


@pytest.mark.parametrize("scenario", ["fixed", "popup", "dynamic"])
@pytest.mark.parametrize("method", ["PSO", "SPSO", "ARPSO"])
@pytest.mark.parametrize("reading", [TEXT, FORGETS, DETECTION], ids=["text", "forgets", "r1"])
def test_legs_match_the_stepped_swarm(scenario: str, method: str, reading: tuple[str, ...]) -> None:
    _same(_profile(scenario, method, *reading), seed=11, runs=40)


def test_a_run_that_confirms_everything_ends_the_loop_as_the_stepped_one_does() -> None:
    """A long T_S cap and one real target: the stepped loop stops at the first step past the
    duration by which every run has confirmed every real target (here 1850 s); the legs
    engine must stop at the same step."""
    only_t2 = [f"targets.{k}.false_target=true" for k in range(10) if k != 1]
    profile = _profile("fixed", "PSO", *TEXT, "mission.ts_cap=40000", *only_t2)
    legs = run_waypoint_swarm_block(profile, 5, 0, 3)
    stepped = stepped_block(profile, 5, 0, 3)
    assert stepped.sim_seconds < 40000 * 3 * 12  # it did stop early
    assert stepped.sim_seconds > profile.mission.duration * 3 * 12
    assert legs.sim_seconds == stepped.sim_seconds
    assert np.array_equal(legs.per_vehicle, stepped.per_vehicle)
    assert (legs.events, legs.followed) == (stepped.events, stepped.followed)


def test_an_interval_that_does_not_add_up_exactly() -> None:
    """0.7 s steps: the times are sums of 0.7, not multiples of it."""
    _same(_profile("dynamic", "ARPSO", *TEXT, "policy.swarm.update_interval=0.7"), 2, 6)


def test_false_targets_are_never_confirmed() -> None:
    """False targets give a signal but are never confirmed (the detection reading reads them)."""
    profile = _profile("popup", "SPSO", *DETECTION, "targets.2.false_target=true")
    _same(profile, seed=9, runs=30)
    assert not np.isfinite(run_waypoint_swarm_block(profile, 9, 1, 30).per_vehicle[..., 2]).any()
