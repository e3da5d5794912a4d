"""Building the search policy from a mission profile."""

from __future__ import annotations

import pytest

from mdm_core.search.distributions import Brownian, Levy, Uniform
from mdm_core.search.from_profile import policy_config, sampler, sensor_for_level
from mdm_profiles import builtin_profile
from mdm_profiles.schema import DistributionParams, LevelSpec, PolicySpec


def test_paper_fixed_profile_gives_ls_then_bs_with_sensor_k_on_level_k() -> None:
    profile = builtin_profile("paper-fixed")
    config = policy_config(profile)
    assert config.label == "MDM (LS+BS)"
    assert [lv.sensor_radius for lv in config.levels] == [2000.0, 400.0]
    assert [lv.step for lv in config.levels] == [4000.0, 2000.0]
    assert config.levels[0].index is None
    assert config.levels[1].index is not None
    assert config.levels[1].index.kappa == 180.0
    assert config.area == (20000.0, 20000.0)
    assert [sensor_for_level(profile, k) for k in (0, 1)] == [0, 1]


def test_single_sensor_profile_uses_only_the_confirmation_sensor() -> None:
    profile = builtin_profile("paper-fixed").with_policy(
        PolicySpec(kind="sss", levels=[LevelSpec(distribution="US", step=4000.0)])
    )
    config = policy_config(profile)
    assert len(config.levels) == 1
    assert config.levels[0].sensor_radius == 400.0
    assert sensor_for_level(profile, 0) == 1


def test_sampler_carries_the_profile_parameters() -> None:
    params = DistributionParams(
        levy_index=1.5, levy_scale=2.0, brownian_sigma=3.0, uniform_low=0.0, uniform_high=1.0
    )
    assert sampler("LS", params) == Levy(index=1.5, scale=2.0)
    assert sampler("BS", params) == Brownian(sigma=3.0)
    assert sampler("US", params) == Uniform(low=0.0, high=1.0)


def test_unknown_distribution_name_lists_the_allowed_ones() -> None:
    with pytest.raises(ValueError, match="allowed: LS, BS, US"):
        sampler("XS", DistributionParams())
