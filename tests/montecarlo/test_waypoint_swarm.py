"""The swarm baselines iterating per waypoint (mdm_montecarlo.engines.waypoint_swarm) and the swarm's
memory options (policy.swarm.after_confirmation, read_confirmed)."""

from __future__ import annotations

import numpy as np
import pytest

from mdm_core.search.from_profile import policy_config
from mdm_core.search.pso import Best
from mdm_montecarlo.engines.runner import run_missions
from mdm_montecarlo.engines.social_engine import run_swarm_block
from mdm_montecarlo.engines.waypoint_swarm import swarm_rules
from mdm_montecarlo.kernels.compiled_step import CompiledPolicy
from mdm_montecarlo.study.cases import Case
from mdm_profiles import MissionProfile
from mdm_profiles.loader import ProfileError
from mdm_profiles.overrides import apply_overrides
from tests.montecarlo.stepped_waypoint_swarm import arrive_reached

WAYPOINT = ("policy.swarm.iteration=waypoint",)
CONFIRMATION = (
    *WAYPOINT,
    "policy.swarm.signal_sensor=confirmation",
    "policy.swarm.after_confirmation=forget",
    "policy.swarm.read_confirmed=false",
)
TEXT = (
    *WAYPOINT,
    "policy.swarm.signal_sensor=confirmation",
    "policy.swarm.after_confirmation=keep",
    "policy.swarm.read_confirmed=true",
)
"""Section IV's reading, the defaults (spelt out: the tests do not depend on them)."""


def _profile(scenario: str, method: str, *settings: str) -> MissionProfile:
    """The simtablepso1 row's profile (simulated up to the mission duration) with settings."""
    return apply_overrides(Case(scenario, method, 20.0, 12, 0).profile(), list(settings))


def test_two_workers_match_one() -> None:
    profile = _profile("popup", "SPSO", *TEXT)
    one = run_missions(profile, runs=60, seed=3, workers=1, block_runs=25)
    two = run_missions(profile, runs=60, seed=3, workers=2, block_runs=25)
    assert np.array_equal(one.team_times, two.team_times)
    assert (one.events, one.followed) == (two.events, two.followed)


def test_an_iteration_lasts_until_the_waypoint_is_reached() -> None:
    """Per interval, every particle iterates every 5 s step; per waypoint, only on arrival:
    a 4 km exploration leg takes many steps, so there are far fewer iterations."""
    interval = run_swarm_block(
        _profile("fixed", "PSO", "policy.swarm.iteration=interval"), 4, 0, 30
    )
    waypoint = run_swarm_block(_profile("fixed", "PSO", *WAYPOINT), 4, 0, 30)
    steps = 1000 / 5
    assert interval.events == steps * 30 * 12
    assert waypoint.events < 0.5 * interval.events
    assert waypoint.events > 30 * 12


def test_confirmation_sensor_alone_forms_no_best_when_confirmed_targets_leave_it() -> None:
    """Read only within r_2, a signal comes from a target already confirmed on the way in; if
    confirmed targets are not read, no best ever forms: nobody follows anyone, and PSO and
    ARPSO (which differ only by their inertia) fly the same missions."""
    pso = run_swarm_block(_profile("fixed", "PSO", *CONFIRMATION), 8, 0, 40)
    arpso = run_swarm_block(_profile("fixed", "ARPSO", *CONFIRMATION), 8, 0, 40)
    assert pso.followed == 0
    assert np.array_equal(pso.per_vehicle, arpso.per_vehicle)
    assert np.isfinite(pso.per_vehicle).any()


def test_kept_bests_of_confirmed_targets_draw_the_swarm_there() -> None:
    """The text's reading (confirmation sensor, standard PSO memory, confirmed targets still
    read): the particles follow the bests of targets found already, and pop-up targets that
    appear elsewhere are found less often than by the same swarm that forgets them."""
    kept = run_missions(_profile("popup", "PSO", *TEXT), runs=200, seed=11)
    forgot = run_missions(_profile("popup", "PSO", *CONFIRMATION), runs=200, seed=11)
    assert kept.follow_share is not None
    assert kept.follow_share > 0.1
    assert forgot.follow_share == 0.0
    print(f"pop-up PSO T_nc: keep {kept.tnc.mean():.3f}, forget {forgot.tnc.mean():.3f}")
    assert kept.tnc.mean() < forgot.tnc.mean() - 0.25


def _arrive_one(
    method: str, rng: np.random.Generator, local_fitness: float = 0.0, informants: int = 2
) -> tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One run of three particles: particle 0 arrives at (1000, 1000) with the swarm's best
    (fitness 0.5, vehicle 1's) 15 km east and SPSO's last local best ``local_fitness``; 1 and 2
    fly on. Returns (followed, position, waypoint, velocity, links) after the arrival step."""
    profile = _profile("fixed", method, *TEXT)
    config = swarm_rules(profile)
    position = np.array([[[1000.0, 1000.0], [16000.0, 1000.0], [500.0, 500.0]]])
    own = Best(position.copy(), np.array([[0.0, 0.5, 0.0]]), np.array([[-1, 3, -1]]))
    reached = np.array([[True, False, False]])
    waypoint = np.array([[[1000.0, 1000.0], [16000.0, 1000.0], [900.0, 900.0]]])
    velocity = np.zeros((1, 3, 2))
    links = np.ones((1, 3, 3), dtype=bool) & ~np.eye(3, dtype=bool)
    followed = arrive_reached(
        config,
        informants,
        CompiledPolicy(policy_config(profile)),
        own,
        reached,
        position,
        np.zeros((1, 3)),
        np.full((1, 3), -1),
        np.zeros((1, 3)),
        velocity,
        waypoint,
        links,
        np.full((1, 3), local_fitness),
        np.array([20000.0, 20000.0]),
        rng,
    )
    return followed, position, waypoint, velocity, links


@pytest.mark.parametrize("method", ["PSO", "SPSO", "ARPSO"])
def test_a_step_toward_a_far_best_is_at_most_delta1(method: str) -> None:
    """A particle that arrives with the swarm's best 15 km away steps at most delta_1 (4 km,
    the single-sensor step) toward it; one that has not arrived keeps its waypoint."""
    delta1 = _profile("fixed", method, *TEXT).policy.levels[0].step
    followed, position, waypoint, velocity, _ = _arrive_one(method, np.random.default_rng(1))
    step = waypoint[0, 0] - position[0, 0]
    assert 0 < np.hypot(*step) <= delta1 + 1e-9
    assert step[0] > 0  # toward the best, east of it
    assert np.array_equal(velocity[0, 0], step)
    assert np.array_equal(waypoint[0, 2], [900.0, 900.0])
    assert followed == 1


@pytest.mark.parametrize(
    ("method", "stuck"), [("PSO", False), ("ARPSO", False), ("SPSO", False), ("SPSO", True)]
)
def test_an_arrival_step_draws_the_arrivals_numbers_only(method: str, stuck: bool) -> None:
    """One particle of three arrives: the step draws its numbers alone, in the documented
    order (PSO/ARPSO r1, r2 per axis; SPSO normals, radius uniform, then its informant keys
    when its local best did not improve), so the generator ends where those draws leave it."""
    rng = np.random.default_rng(5)
    # SPSO with informants=1: the stuck particle's new link follows its smallest key.
    _, _, _, _, links = _arrive_one(method, rng, local_fitness=0.9 if stuck else 0.0, informants=1)
    want = np.random.default_rng(5)
    if method == "SPSO":
        want.standard_normal((1, 1, 2))
        want.random((1, 1))
        if stuck:
            keys = want.random(3)
            keys[0] = np.inf
            assert np.array_equal(links[0, 0], keys == keys.min())
    else:
        want.random((2, 1, 1, 2))
    assert rng.bit_generator.state == want.bit_generator.state


def test_waypoint_iterations_refuse_delayed_or_lost_messages() -> None:
    with pytest.raises(
        ProfileError, match=r"policy\.swarm: .*iteration .waypoint.*message_drop must be 0"
    ):
        _profile("fixed", "PSO", *WAYPOINT, "policy.swarm.message_drop=0.5")
