"""Every case that used to hang the engine or crash the CLI: each now finishes or is refused
with the field named."""

from __future__ import annotations

import numpy as np
import pytest

from mdm_core.search.distributions import Uniform
from mdm_core.search.levels import Level, OutOfArea, PolicyConfig
from mdm_core.search.planar import length
from mdm_core.search.policy import SearchPolicy
from mdm_montecarlo.commands.cli import main
from mdm_montecarlo.engines.runner import run_missions
from mdm_montecarlo.study.variants import with_method
from mdm_profiles import ProfileError, load_profile
from mdm_profiles.overrides import apply_overrides

AREA = 20_000.0


@pytest.mark.parametrize("rule", ["redraw", "clip", "reflect"])
def test_a_vehicle_in_the_corner_with_north_east_only_steps_always_moves(rule: OutOfArea) -> None:
    # US with the printed bounds v_l = 0, v_u = 1 only steps north-east: from the NE corner
    # every candidate is outside. The waypoint must still differ from the position.
    policy = SearchPolicy(
        PolicyConfig(
            levels=(Level(sampler=Uniform(low=0.0, high=1.0), step=4000.0, sensor_radius=400.0),),
            area=(AREA, AREA),
            out_of_area=rule,
        )
    )
    corner = np.full((500, 2), AREA)
    state = policy.start(corner, np.zeros(500), np.random.default_rng(1))
    leg = length(state.waypoint - corner)
    assert leg.min() > 1.0
    assert ((state.waypoint >= 0) & (state.waypoint <= AREA)).all()


@pytest.mark.timeout(120)
def test_printed_us_bounds_finish_and_advance_time() -> None:
    profile = apply_overrides(
        with_method(load_profile("paper-fixed"), "US"), ["policy.distributions.uniform_low=0"]
    )
    res = run_missions(profile, runs=20, seed=3)
    # Every vehicle-second up to the T_S cap is simulated: time advanced to the end.
    lanes = 20 * profile.fleet.vehicles
    assert res.sim_seconds >= 0.99 * lanes * profile.mission.duration
    assert res.events < 20 * lanes * profile.mission.ts_cap / 200  # legs of >= 1 km


@pytest.mark.parametrize(
    ("setting", "named"),
    [
        ("fleet.speed=1e9", "fleet.speed: Input should be less than or equal to 300"),
        (
            "mission.duration=1e12",
            "mission.duration: Input should be less than or equal to 1000000",
        ),
        ("mission.ts_cap=1e12", "mission.ts_cap: Input should be less than or equal to 1000000"),
        ("policy.levels.1.step=0.001", "policy.levels.1.step: Input should be greater than"),
        ("policy.levels.5.step=1", "policy.levels has 2 entries (0 to 1), no 5"),
        ("policy.levels.x.step=1", "policy.levels is a list; expected an index, got 'x'"),
        ("target_motion.speed=3", "target_motion is not set in this profile"),
        ("policy.levels.1.step=2", "the shortest policy.levels step (2 m) = 4e+05 legs"),
        ("policy.swarm.update_interval=0.01", "policy.swarm.update_interval: Input should be"),
    ],
)
def test_absurd_values_are_refused_naming_the_field(setting: str, named: str) -> None:
    with pytest.raises(ProfileError) as err:
        apply_overrides(load_profile("paper-fixed"), [setting])
    assert named in str(err.value)


def test_cli_refuses_a_bad_level_index_without_a_traceback(
    capsys: pytest.CaptureFixture[str],
) -> None:
    argv = ["run", "--profile", "paper-fixed", "--set", "policy.levels.5.step=1", "--runs", "2"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "policy.levels has 2 entries (0 to 1), no 5" in err
    assert "Traceback" not in err


@pytest.mark.timeout(120)
@pytest.mark.parametrize(
    "setting",
    [
        "policy.detection_memory=disc",
        "policy.detection_memory=exact",
        "policy.detection_memory=none",
        "policy.fallback_blind_time=100",
        "policy.levels.1.index.start=max",
    ],
)
def test_every_memory_and_fall_back_option_runs_to_the_end(setting: str) -> None:
    # The engine leaves out of a leg's contacts exactly what the policy would drop; a
    # mismatch would report the same contact again at the same instant, forever.
    profile = apply_overrides(load_profile("paper-dynamic"), [setting])
    res = run_missions(profile, runs=20, seed=5)
    assert res.sim_seconds >= 20 * profile.fleet.vehicles * profile.mission.duration * 0.99
    assert res.tnc.mean() > 1.0
