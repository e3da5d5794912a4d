"""Two samples of one metric set side by side: the difference of their means with its
confidence interval (Welch), a rank test (Mann-Whitney U), a bootstrap interval of the
difference, and effect sizes (Cohen's d, the rank-biserial correlation).

The difference is always B - A. The tests assume independent samples: two configurations
compared with the same seed share their targets and start points (common random numbers),
so `compare` runs configuration B with its own seed unless told otherwise.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

CONFIDENCE = 0.95
BOOTSTRAP_SEED = 0
"""The bootstrap's resampling stream: fixed, so a comparison prints the same numbers twice."""


@dataclass(frozen=True)
class Comparison:
    """One metric of sample B against sample A."""

    metric: str
    n_a: int
    n_b: int
    mean_a: float
    mean_b: float
    difference: float
    """mean B - mean A."""
    ci95: tuple[float, float]
    """Welch's 95 % interval of the difference (unequal variances)."""
    welch_p: float
    mann_whitney_u: float
    """U of sample B (the number of (a, b) pairs with b > a, ties counting half)."""
    mann_whitney_p: float
    """Two-sided p of the rank test (normal approximation with the tie correction)."""
    bootstrap_ci95: tuple[float, float]
    """Percentile interval of the difference of means over resamples of both samples."""
    bootstrap_resamples: int
    cohens_d: float
    """Difference over the pooled standard deviation (nan where both samples are constant)."""
    rank_biserial: float
    """2 U / (n_a n_b) - 1, in [-1, 1]: > 0 where B tends to be larger."""

    def as_dict(self) -> dict[str, object]:
        return asdict(self)


def compare_samples(
    metric: str,
    a: NDArray[np.floating] | NDArray[np.integer],
    b: NDArray[np.floating] | NDArray[np.integer],
    *,
    resamples: int = 10_000,
) -> Comparison:
    """Compare sample ``b`` with sample ``a`` (each needs at least two values)."""
    from scipy.special import stdtrit

    x, y = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if len(x) < 2 or len(y) < 2:
        raise ValueError(f"{metric}: each sample needs at least 2 runs (got {len(x)}, {len(y)})")
    na, nb = len(x), len(y)
    va, vb = x.var(ddof=1), y.var(ddof=1)
    diff = float(y.mean() - x.mean())
    se = float(np.sqrt(va / na + vb / nb))
    if se > 0:
        df = se**4 / ((va / na) ** 2 / (na - 1) + (vb / nb) ** 2 / (nb - 1))
        half = float(stdtrit(df, 0.5 + CONFIDENCE / 2)) * se
        welch_p = float(2 * _t_sf(abs(diff) / se, df))
    else:
        half, welch_p = 0.0, (1.0 if diff == 0 else 0.0)
    u, u_p = _mann_whitney(y, x)
    pooled = np.sqrt(((na - 1) * va + (nb - 1) * vb) / (na + nb - 2))
    low, high = _bootstrap(x, y, resamples)
    return Comparison(
        metric=metric,
        n_a=na,
        n_b=nb,
        mean_a=float(x.mean()),
        mean_b=float(y.mean()),
        difference=diff,
        ci95=(diff - half, diff + half),
        welch_p=welch_p,
        mann_whitney_u=u,
        mann_whitney_p=u_p,
        bootstrap_ci95=(low, high),
        bootstrap_resamples=resamples,
        cohens_d=float(diff / pooled) if pooled > 0 else float("nan"),
        rank_biserial=float(2 * u / (na * nb) - 1),
    )


def _mann_whitney(y: NDArray[np.float64], x: NDArray[np.float64]) -> tuple[float, float]:
    """U of sample y against x (ties count half) and its two-sided p: the normal approximation
    with the tie correction and a continuity correction of 1/2, as scipy.stats.mannwhitneyu's
    method="asymptotic" computes it (whose import alone costs reproduce about 0.45 CPU-s)."""
    from scipy.special import ndtr

    ny, nx = len(y), len(x)
    n = ny + nx
    _, where, counts = np.unique(np.concatenate([y, x]), return_inverse=True, return_counts=True)
    # The average rank of each distinct value (ranks from 1), summed over y's values.
    ranks = np.cumsum(counts) - (counts - 1) / 2.0
    u = float(ranks[where[:ny]].sum()) - ny * (ny + 1) / 2.0
    ties = float((counts.astype(float) ** 3 - counts).sum())
    sigma = np.sqrt(ny * nx / 12.0 * ((n + 1) - ties / (n * (n - 1))))
    excess = max(u, ny * nx - u) - ny * nx / 2.0
    if sigma == 0:
        return u, 1.0
    p = 2.0 * float(ndtr(-(excess - 0.5) / sigma))
    return u, min(max(p, 0.0), 1.0)


def _t_sf(t: float, df: float) -> float:
    """P(T > t) of Student's t with ``df`` degrees of freedom."""
    from scipy.special import stdtr

    return float(stdtr(df, -t))


def _bootstrap(
    x: NDArray[np.float64], y: NDArray[np.float64], resamples: int
) -> tuple[float, float]:
    """Percentile interval of mean(y*) - mean(x*), each sample resampled with replacement."""
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    diffs = _resampled_means(y, resamples, rng) - _resampled_means(x, resamples, rng)
    tail = (1 - CONFIDENCE) / 2
    low, high = np.quantile(diffs, [tail, 1 - tail])
    return float(low), float(high)


def _resampled_means(
    values: NDArray[np.float64], resamples: int, rng: np.random.Generator
) -> NDArray[np.float64]:
    """Means of ``resamples`` resamples of ``values``. A sample of few distinct values (T_nc:
    0 to the number of targets) is resampled as multinomial counts of those values, the same
    law at a fraction of the draws; others run by run, in chunks of a few MB."""
    n = len(values)
    distinct, counts = np.unique(values, return_counts=True)
    if len(distinct) <= 64:
        drawn = rng.multinomial(n, counts / n, size=resamples)
        return np.asarray(drawn @ distinct / n, dtype=np.float64)
    means = np.empty(resamples)
    chunk = max(1, 2_000_000 // n)
    for start in range(0, resamples, chunk):
        k = min(chunk, resamples - start)
        means[start : start + k] = values[rng.integers(0, n, size=(k, n))].mean(axis=1)
    return means


def format_comparisons(label_a: str, label_b: str, rows: list[Comparison]) -> str:
    """A Markdown table of comparisons of B against A."""
    lines = [
        f"A = {label_a}; B = {label_b}. Difference = mean B - mean A.",
        "",
        "| metric | runs A | runs B | mean A | mean B | difference | 95 % CI (Welch) |"
        " p (Welch) | Mann-Whitney U | p (U) | bootstrap 95 % CI | Cohen's d | rank-biserial |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for c in rows:
        fmt = ".3f" if c.metric == "T_nc" else ".0f"
        lines.append(
            f"| {c.metric} | {c.n_a} | {c.n_b} | {c.mean_a:{fmt}} | {c.mean_b:{fmt}} | "
            f"{c.difference:+{fmt}} | [{c.ci95[0]:{fmt}}, {c.ci95[1]:{fmt}}] | {c.welch_p:.2g} | "
            f"{c.mann_whitney_u:.0f} | {c.mann_whitney_p:.2g} | "
            f"[{c.bootstrap_ci95[0]:{fmt}}, {c.bootstrap_ci95[1]:{fmt}}] | {c.cohens_d:+.2f} | "
            f"{c.rank_biserial:+.2f} |"
        )
    return "\n".join(lines)
