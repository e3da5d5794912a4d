"""Direction samplers of eq. (7)-(11) against their distributions."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from mdm_core.search.distributions import (
    Brownian,
    Levy,
    Sampler,
    Uniform,
    directions,
    symmetric_stable,
)

N = 20_000


def _ks_stat_bound(n: int) -> float:
    # 1.63/sqrt(n) is the 1 % critical value of the KS statistic.
    return float(1.63 / np.sqrt(n))


def test_levy_index_1_scale_1_is_standard_cauchy() -> None:
    x = Levy(index=1.0, scale=1.0).draw(np.random.default_rng(1), (N,))
    result = stats.kstest(x, stats.cauchy().cdf)
    assert result.statistic < _ks_stat_bound(N)


def test_levy_index_1_scale_alpha_is_cauchy_of_scale_alpha() -> None:
    x = Levy(index=1.0, scale=3.0).draw(np.random.default_rng(2), (N,))
    assert stats.kstest(x, stats.cauchy(scale=3.0).cdf).statistic < _ks_stat_bound(N)
    # A unit-scale Cauchy is clearly rejected: the scale is really applied.
    assert stats.kstest(x, stats.cauchy().cdf).statistic > 3 * _ks_stat_bound(N)


def test_levy_index_2_is_normal_with_variance_two() -> None:
    x = Levy(index=2.0, scale=1.0).draw(np.random.default_rng(3), (N,))
    assert stats.kstest(x, stats.norm(0.0, np.sqrt(2.0)).cdf).statistic < _ks_stat_bound(N)
    assert stats.kstest(x, stats.norm(0.0, 1.0).cdf).statistic > 3 * _ks_stat_bound(N)


@pytest.mark.parametrize(
    ("index", "scale"), [(0.5, 1.0), (1.0, 1.0), (1.5, 1.0), (1.5, 2.0), (2.0, 0.5)]
)
def test_levy_characteristic_function_matches_paper_integral(index: float, scale: float) -> None:
    """Eq. (8) is the inverse transform of exp(-alpha |m|^lambda); E[cos(m X)] must equal it."""
    x = Levy(index=index, scale=scale).draw(np.random.default_rng(4), (200_000,))
    for m in (0.25, 0.5, 1.0, 2.0):
        empirical = np.mean(np.cos(m * x))
        assert empirical == pytest.approx(np.exp(-scale * m**index), abs=0.01)


def test_levy_index_1_5_matches_scipy_levy_stable_quantiles() -> None:
    x = Levy(index=1.5, scale=1.0).draw(np.random.default_rng(5), (100_000,))
    probs = np.array([0.1, 0.25, 0.75, 0.9])
    expected = stats.levy_stable(1.5, 0.0, scale=1.0).ppf(probs)
    assert np.quantile(x, probs) == pytest.approx(expected, abs=0.03)


@pytest.mark.parametrize("index", [0.0, -1.0, 2.01])
def test_stable_index_outside_0_2_is_rejected(index: float) -> None:
    with pytest.raises(ValueError, match="lambda"):
        symmetric_stable(np.random.default_rng(0), index, 1.0, (3,))


def test_brownian_is_normal_with_sigma() -> None:
    x = Brownian(sigma=3.0).draw(np.random.default_rng(6), (N,))
    assert stats.kstest(x, stats.norm(0.0, 3.0).cdf).statistic < _ks_stat_bound(N)


@pytest.mark.parametrize(("low", "high"), [(-1.0, 1.0), (0.0, 1.0), (2.0, 5.0)])
def test_uniform_is_uniform_on_low_high(low: float, high: float) -> None:
    x = Uniform(low=low, high=high).draw(np.random.default_rng(7), (N,))
    assert stats.kstest(x, stats.uniform(low, high - low).cdf).statistic < _ks_stat_bound(N)
    assert x.min() >= low
    assert x.max() <= high


def test_uniform_with_empty_interval_is_rejected() -> None:
    with pytest.raises(ValueError, match="v_u > v_l"):
        Uniform(low=1.0, high=1.0)


@pytest.mark.parametrize("sampler", [Levy(), Levy(index=1.5), Brownian(), Uniform()])
def test_directions_are_unit_vectors(sampler: Sampler) -> None:
    d = directions(sampler, np.random.default_rng(8), 5000)
    assert d.shape == (5000, 2)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-12)


def _angles(sampler: Sampler, seed: int, n: int = N) -> np.ndarray:
    d = directions(sampler, np.random.default_rng(seed), n)
    return np.arctan2(d[:, 1], d[:, 0])


def _near_axes(angles: np.ndarray, degrees: float = 10.0) -> float:
    quadrant = np.mod(angles, np.pi / 2)
    return float(np.mean(np.minimum(quadrant, np.pi / 2 - quadrant) < np.radians(degrees)))


def test_brownian_direction_angle_is_uniform_on_the_circle() -> None:
    angles = _angles(Brownian(sigma=2.0), 9)
    uniform = stats.uniform(-np.pi, 2 * np.pi).cdf
    assert stats.kstest(angles, uniform).statistic < _ks_stat_bound(N)


def test_levy_direction_angle_concentrates_near_the_axes() -> None:
    # Uniform angles put 20/90 = 0.222 of the mass within 10 degrees of an axis; heavy tails
    # make one sample dominate, so Cauchy directions hug the axes (about 0.39).
    assert _near_axes(_angles(Levy(), 10)) > 0.35
    assert _near_axes(_angles(Brownian(), 10)) == pytest.approx(2 / 9, abs=0.015)


def test_levy_direction_angle_is_not_uniform() -> None:
    angles = _angles(Levy(), 11)
    uniform = stats.uniform(-np.pi, 2 * np.pi).cdf
    assert stats.kstest(angles, uniform).pvalue < 1e-6


def test_uniform_zero_one_directions_point_into_first_quadrant_only() -> None:
    d = directions(Uniform(low=0.0, high=1.0), np.random.default_rng(12), 2000)
    assert np.all(d >= 0.0)


def test_same_seed_gives_same_directions() -> None:
    a = directions(Levy(), np.random.default_rng(13), 100)
    b = directions(Levy(), np.random.default_rng(13), 100)
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("index", [1.0, 1.5])
def test_stable_draws_use_the_c_library_on_every_cpu(index: float) -> None:
    """The same draw as the Chambers-Mallows-Stuck formula element by element with Python's
    math (the C library), to the bit: numpy's tan and power round otherwise on AVX-512 CPUs,
    which made a seeded draw machine-dependent and unequal to the compiled engine's."""
    got = symmetric_stable(np.random.default_rng(5), index, 2.0, (4000,))
    rng = np.random.default_rng(5)
    v = rng.uniform(-np.pi / 2, np.pi / 2, 4000).tolist()
    w = rng.exponential(1.0, 4000).tolist()
    scale = 2.0 ** (1.0 / index)
    if index == 1.0:
        want = [math.tan(a) * scale for a in v]
    else:
        want = [
            math.sin(index * a)
            / math.cos(a) ** (1.0 / index)
            * (math.cos(a - index * a) / b) ** ((1.0 - index) / index)
            * scale
            for a, b in zip(v, w, strict=True)
        ]
    np.testing.assert_array_equal(got, np.array(want))
