"""The paper's metrics: T_nc (targets confirmed in a fixed time) and T_S (time to confirm all).

Every function takes first-confirmation times: ``times[run, target]`` is the earliest time any
vehicle of the run confirmed that target (inf if none did). False targets are never confirmed and
do not count towards "all targets".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def team_times(per_vehicle: FloatArray) -> FloatArray:
    """(runs, vehicles, targets) first confirmations per vehicle -> (runs, targets) per team."""
    return np.asarray(per_vehicle.min(axis=1))


def confirmed_within(times: FloatArray, horizon: float) -> NDArray[np.int64]:
    """T_nc: distinct targets confirmed at or before ``horizon`` seconds, per run."""
    return np.asarray((times <= horizon).sum(axis=1), dtype=np.int64)


def time_to_all(
    times: FloatArray, real: BoolArray, cap: float, gone: FloatArray | None = None
) -> tuple[FloatArray, BoolArray]:
    """T_S per run, and whether it was capped (not every real target confirmed by ``cap``).

    ``gone`` (runs, targets): when each target left the area (inf: never); given, a target
    counts as searched at its confirmation or its departure, whichever is first
    (``mission.ts_rule: confirmed_or_gone``).
    """
    if gone is not None:
        times = np.minimum(times, gone)
    last = np.where(real[None, :], times, -np.inf).max(axis=1)
    capped = ~(last <= cap)
    return np.where(capped, cap, last), capped


@dataclass(frozen=True)
class Summary:
    """Mean, standard deviation and a 95 % confidence interval of the mean."""

    mean: float
    std: float
    ci_low: float
    ci_high: float
    n: int

    @classmethod
    def of(cls, values: NDArray[np.generic]) -> Summary:
        # stdtrit(df, p) is what scipy.stats.t.ppf(p, df) evaluates (scipy.special alone is a
        # third of scipy.stats' import time). Imported here, not at the top: `reproduce` starts
        # its simulation workers before it needs a summary, and they never do.
        from scipy.special import stdtrit

        values = np.asarray(values, dtype=float)
        n = len(values)
        mean = float(values.mean()) if n else float("nan")
        std = float(values.std(ddof=1)) if n > 1 else 0.0
        half = float(stdtrit(n - 1, 0.975) * std / np.sqrt(n)) if n > 1 else float("nan")
        return cls(mean, std, mean - half, mean + half, n)


def aise(tnc_mdm: float, tnc_sss: float) -> float | None:
    """Average improvement in search efficiency, percent (section IV); None where the baseline
    confirmed nothing (a percentage of zero is undefined: few runs, say)."""
    return (tnc_mdm - tnc_sss) / tnc_sss * 100.0 if tnc_sss else None


def aisc(ts_mdm: float, ts_sss: float) -> float | None:
    """Average improvement in search completeness, percent (section IV); None where the
    baseline's T_S is zero."""
    return (ts_sss - ts_mdm) / ts_sss * 100.0 if ts_sss else None
