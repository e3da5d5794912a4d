"""Direction samplers D(S_t) of eq. (7): Levy (LS), Brownian (BS) and uniform (US).

Each sampler draws the two samples (s_x, s_y) of section III; the direction is their normalised
vector. Levy samples are symmetric alpha-stable with index lambda and scale alpha, drawn with the
Chambers-Mallows-Stuck method (the algorithm cited by the paper as [levy1]).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np
from numpy.typing import NDArray

from mdm_core import libm
from mdm_core.search.planar import length

FloatArray = NDArray[np.float64]
DistributionName = Literal["LS", "BS", "US"]


class Sampler(Protocol):
    """Draws raw samples of one stochastic process."""

    @property
    def name(self) -> DistributionName:
        """LS, BS or US."""
        ...

    def draw(self, rng: np.random.Generator, size: tuple[int, ...]) -> FloatArray:
        """Samples of the given shape."""
        ...


def symmetric_stable(
    rng: np.random.Generator, index: float, scale: float, size: tuple[int, ...]
) -> FloatArray:
    """Symmetric alpha-stable samples (characteristic function exp(-scale |m|^index)).

    Chambers-Mallows-Stuck: V ~ U(-pi/2, pi/2), W ~ Exp(1). Index 1 is Cauchy, index 2 is normal
    with variance 2 scale^2 (note: the paper's integral uses scale alpha directly in the exponent).
    The transcendental functions are the C library's (mdm_core.libm), the same on every machine.
    """
    if not 0 < index <= 2:
        raise ValueError(f"stable index lambda must be in (0, 2], got {index}")
    v = rng.uniform(-np.pi / 2, np.pi / 2, size=size)
    w = rng.exponential(1.0, size=size)
    if abs(index - 1.0) < 1e-12:
        x = libm.tan(v)
    else:
        x = (
            libm.sin(index * v)
            / libm.power(libm.cos(v), 1.0 / index)
            * libm.power(libm.cos(v - index * v) / w, (1.0 - index) / index)
        )
    # The paper's density exp(-alpha m^lambda) has scale alpha^(1/lambda) in the usual sense.
    return np.asarray(x * scale ** (1.0 / index), dtype=np.float64)


@dataclass(frozen=True)
class Levy:
    """LS: symmetric alpha-stable samples, eq. (8)."""

    index: float = 1.0
    """lambda, 0 < lambda <= 2 (paper: 1)."""
    scale: float = 1.0
    """alpha, the scaling parameter (paper: 1)."""
    name: DistributionName = "LS"

    def draw(self, rng: np.random.Generator, size: tuple[int, ...]) -> FloatArray:
        return symmetric_stable(rng, self.index, self.scale, size)


@dataclass(frozen=True)
class Brownian:
    """BS: zero-mean normal samples, eq. (9)."""

    sigma: float = 1.0
    """Standard deviation (paper: 1)."""
    name: DistributionName = "BS"

    def draw(self, rng: np.random.Generator, size: tuple[int, ...]) -> FloatArray:
        return rng.normal(0.0, self.sigma, size=size)


@dataclass(frozen=True)
class Uniform:
    """US: samples uniform on [low, high], eq. (11).

    The paper prints v_l = 0, v_u = 1, which only points into one quadrant; the default here is
    the symmetric [-1, 1] (docs/model.md measures both).
    """

    low: float = -1.0
    """v_l."""
    high: float = 1.0
    """v_u."""
    name: DistributionName = "US"

    def __post_init__(self) -> None:
        if not self.high > self.low:
            raise ValueError(f"uniform bounds need v_u > v_l, got [{self.low}, {self.high}]")

    def draw(self, rng: np.random.Generator, size: tuple[int, ...]) -> FloatArray:
        return rng.uniform(self.low, self.high, size=size)


def directions(sampler: Sampler, rng: np.random.Generator, n: int) -> FloatArray:
    """n unit vectors (n, 2): two samples per vector, normalised (section III, eq. 7)."""
    raw = sampler.draw(rng, (n, 2))
    norm = length(raw)
    zero = norm == 0.0
    if zero.any():
        # Probability zero for these laws; fall back to north to stay finite.
        raw[zero] = (1.0, 0.0)
        norm[zero] = 1.0
    raw /= norm[:, None]
    return raw
