"""The decaying index C_I of section III, and the validation of levels and policies."""

from __future__ import annotations

import numpy as np
import pytest

from mdm_core.search.distributions import Brownian, Levy, Uniform
from mdm_core.search.levels import DecayIndex, Level, PolicyConfig


def test_index_starts_at_gamma_plus_max_minus_min() -> None:
    index = DecayIndex(gamma=0.1, index_max=0.95, index_min=0.2, kappa=150.0)
    assert float(index.value(np.array(0.0))) == pytest.approx(0.1 + 0.95 - 0.2, abs=1e-15)


def test_index_follows_the_exponential_formula() -> None:
    index = DecayIndex(gamma=0.05, index_max=0.9, index_min=0.3, kappa=40.0)
    t = np.array([0.0, 1.0, 10.0, 40.0, 1000.0])
    np.testing.assert_allclose(index.value(t), 0.05 + 0.6 * np.exp(-t / 40.0), rtol=1e-15)
    assert np.all(np.diff(index.value(t)) < 0)


def test_paper_lifetime_is_kappa_ln_7_5() -> None:
    assert DecayIndex().lifetime == pytest.approx(150.0 * np.log(0.75 / 0.1), rel=1e-15)


@pytest.mark.parametrize(
    ("gamma", "index_max", "index_min", "kappa"),
    [(0.1, 0.95, 0.2, 150.0), (0.01, 0.99, 0.4, 3.0), (0.2, 0.6, 0.3, 1000.0)],
)
def test_index_equals_its_minimum_exactly_at_the_lifetime(
    gamma: float, index_max: float, index_min: float, kappa: float
) -> None:
    index = DecayIndex(gamma=gamma, index_max=index_max, index_min=index_min, kappa=kappa)
    life = index.lifetime
    assert float(index.value(np.array(life))) == pytest.approx(index_min, abs=1e-9)
    assert float(index.value(np.array(life * (1 - 1e-6)))) > index_min
    assert float(index.value(np.array(life * (1 + 1e-6)))) < index_min


@pytest.mark.parametrize(
    ("gamma", "index_max", "index_min"),
    [(0.0, 0.95, 0.2), (0.2, 0.95, 0.2), (0.1, 0.2, 0.3), (0.1, 0.25, 0.2)],
)
def test_index_with_out_of_order_constants_is_rejected(
    gamma: float, index_max: float, index_min: float
) -> None:
    with pytest.raises(ValueError, match="decay index"):
        DecayIndex(gamma=gamma, index_max=index_max, index_min=index_min)


def test_index_with_nonpositive_kappa_is_rejected() -> None:
    with pytest.raises(ValueError, match="kappa"):
        DecayIndex(kappa=0.0)


@pytest.mark.parametrize(("step", "radius"), [(0.0, 400.0), (-1.0, 400.0), (100.0, 0.0)])
def test_level_with_nonpositive_step_or_radius_is_rejected(step: float, radius: float) -> None:
    with pytest.raises(ValueError, match="> 0 m"):
        Level(sampler=Brownian(), step=step, sensor_radius=radius)


def _levels() -> tuple[Level, Level]:
    return (
        Level(sampler=Levy(), step=4000.0, sensor_radius=2000.0),
        Level(sampler=Brownian(), step=2000.0, sensor_radius=400.0, index=DecayIndex()),
    )


def test_policy_without_levels_is_rejected() -> None:
    with pytest.raises(ValueError, match="at least one level"):
        PolicyConfig(levels=(), area=(100.0, 100.0))


def test_policy_with_index_on_level_1_is_rejected() -> None:
    one, two = _levels()
    with pytest.raises(ValueError, match="level 1 has no decaying index"):
        PolicyConfig(levels=(two, two), area=(100.0, 100.0))
    assert one.index is None


def test_policy_without_index_on_level_2_is_rejected() -> None:
    one, _ = _levels()
    with pytest.raises(ValueError, match="level 2 needs a decaying index"):
        PolicyConfig(levels=(one, one), area=(100.0, 100.0))


def test_policy_with_negative_memory_radius_is_rejected() -> None:
    with pytest.raises(ValueError, match="memory_radius"):
        PolicyConfig(levels=_levels(), area=(100.0, 100.0), memory_radius=-1.0)


def test_policy_label_names_the_distributions() -> None:
    assert PolicyConfig(levels=_levels(), area=(1.0, 1.0)).label == "MDM (LS+BS)"
    single = (Level(sampler=Uniform(), step=1.0, sensor_radius=1.0),)
    assert PolicyConfig(levels=single, area=(1.0, 1.0)).label == "US"
    assert PolicyConfig(levels=single, area=(1.0, 1.0), name="x").label == "x"
