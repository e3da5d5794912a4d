"""Throughput of the Monte-Carlo engine, and its agreement with the dt = 0.1 s reference.

    .venv/bin/python benchmarks/montecarlo_throughput.py [--runs 4000] [--ref-runs 100]
    .venv/bin/python benchmarks/montecarlo_throughput.py --profile paper-dynamic --workers 2

1. Engine: paper-fixed (or ``--profile``) flown with MDM (LS+BS) and the single-sensor searches
   US, BS, LS, ``--runs`` missions each (full T_S runs, up to the profile's ts_cap), with 1 and 2
   local workers: wall time, missions per second, simulated UAV-seconds per wall second.
2. Reference (mdm_montecarlo.engines.reference, full tau-lag dynamics, sensors read every dt) on
   ``--ref-runs`` missions at ``--ref-dt``: the same figures.
3. Agreement of T_nc (targets confirmed in the mission duration) between the engine's runs of
   step 1 and the reference, same seed: means with standard errors, their difference, the
   two-sided Mann-Whitney U test and a chi-square test on the counts of T_nc values.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from numpy.typing import NDArray
from scipy import stats

from mdm_core import metrics
from mdm_montecarlo.engines.reference import run_reference
from mdm_montecarlo.engines.runner import MissionResults, run_missions
from mdm_montecarlo.study.variants import with_method
from mdm_profiles import load_profile

ENGINE_METHODS = ("MDM:LS+BS", "US", "BS", "LS")


def _chi_square(a: NDArray[np.int64], b: NDArray[np.int64]) -> tuple[float, float]:
    """Chi-square test of homogeneity on the T_nc histograms (sparse tail bins pooled)."""
    values = np.arange(max(int(a.max()), int(b.max())) + 1)
    table = np.array([[np.sum(x == v) for v in values] for x in (a, b)], dtype=float)
    # Pool neighbouring bins until every expected count is >= 5 (the test's usual condition).
    bins: list[NDArray[np.float64]] = []
    acc = np.zeros(2)
    for col in table.T:
        acc = acc + col
        expected = acc.sum() * table.sum(axis=1) / table.sum()
        if expected.min() >= 5:
            bins.append(acc)
            acc = np.zeros(2)
    if acc.sum() > 0:
        if bins:
            bins[-1] = bins[-1] + acc
        else:
            bins.append(acc)
    pooled = np.array(bins).T
    if pooled.shape[1] < 2:
        return 0.0, 1.0
    res = stats.chi2_contingency(pooled)
    return float(res.statistic), float(res.pvalue)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    parser.add_argument(
        "--runs", type=int, default=4000, help="engine missions per method (4 blocks of 1000)"
    )
    parser.add_argument("--ref-runs", type=int, default=100, help="reference missions per method")
    parser.add_argument("--ref-dt", type=float, default=0.1, help="reference time step, s")
    parser.add_argument(
        "--ref-methods",
        default="MDM:LS+BS,US",
        help="comma-separated methods to check against the reference",
    )
    parser.add_argument("--workers", default="1,2", help="comma-separated local worker counts")
    parser.add_argument("--seed", type=int, default=2024)
    parser.add_argument("--profile", default="paper-fixed", help="built-in profile or YAML path")
    parser.add_argument(
        "--step-every-lane",
        action="store_true",
        help="reference: step the policy for every lane every dt (bit-identical, slower)",
    )
    args = parser.parse_args()
    workers = [int(w) for w in args.workers.split(",")]
    base = load_profile(args.profile)
    vehicles = base.fleet.vehicles

    print(f"{base.name}, {vehicles} UAVs, duration {base.mission.duration:g} s, seed {args.seed}")
    print("\nEngine (event-driven), full runs to T_S (cap", f"{base.mission.ts_cap:g} s)")
    header = f"{'method':<10} {'workers':>7} {'runs':>6} {'wall s':>8} {'missions/s':>11}"
    print(header + f" {'UAV-s/s':>12} {'mean T_nc':>9}")
    engine: dict[str, MissionResults] = {}
    for method in ENGINE_METHODS:
        profile = with_method(base, method)
        for w in workers:
            t0 = time.perf_counter()
            res = run_missions(profile, runs=args.runs, seed=args.seed, workers=w)
            wall = time.perf_counter() - t0
            engine.setdefault(method, res)
            print(
                f"{method:<10} {w:>7} {res.runs:>6} {wall:>8.2f} {res.runs / wall:>11.1f}"
                f" {res.sim_seconds / wall:>12.3e} {res.tnc.mean():>9.3f}"
            )

    mode = "every lane" if args.step_every_lane else "busy lanes (bit-identical)"
    print(f"\nReference (dt = {args.ref_dt:g} s, tau-lag + pursuit, policy stepped on {mode})")
    print(f"{'method':<10} {'runs':>6} {'wall s':>8} {'missions/s':>11} {'UAV-s/s':>12}")
    compare = []
    for method in [m.strip() for m in args.ref_methods.split(",") if m.strip()]:
        profile = with_method(base, method)
        t0 = time.perf_counter()
        ref = run_reference(
            profile,
            runs=args.ref_runs,
            seed=args.seed,
            dt=args.ref_dt,
            step_every_lane=args.step_every_lane,
        )
        wall = time.perf_counter() - t0
        runs = ref.per_vehicle.shape[0]
        print(
            f"{method:<10} {runs:>6} {wall:>8.2f} {runs / wall:>11.2f}"
            f" {ref.sim_seconds / wall:>12.3e}"
        )
        tnc = metrics.confirmed_within(metrics.team_times(ref.per_vehicle), base.mission.duration)
        if method not in engine:
            engine[method] = run_missions(profile, runs=args.runs, seed=args.seed)
        compare.append((method, tnc, engine[method].tnc))

    print(f"\nT_nc agreement, engine ({args.runs} runs) vs reference ({args.ref_runs} runs)")
    print(
        f"{'method':<10} {'engine':>15} {'reference':>15} {'diff':>7} {'SE diff':>8}"
        f" {'U':>9} {'p(MWU)':>7} {'chi2':>7} {'p(chi2)':>7}"
    )
    for method, ref_tnc, eng_tnc in compare:
        se_e = eng_tnc.std(ddof=1) / np.sqrt(len(eng_tnc))
        se_r = ref_tnc.std(ddof=1) / np.sqrt(len(ref_tnc))
        mwu = stats.mannwhitneyu(eng_tnc, ref_tnc, alternative="two-sided")
        chi2, p_chi2 = _chi_square(eng_tnc, ref_tnc)
        diff = eng_tnc.mean() - ref_tnc.mean()
        print(
            f"{method:<10} {eng_tnc.mean():>7.3f}+-{se_e:<6.3f} {ref_tnc.mean():>7.3f}+-{se_r:<6.3f}"
            f" {diff:>+7.3f} {np.hypot(se_e, se_r):>8.3f} {mwu.statistic:>9.1f} {mwu.pvalue:>7.3f}"
            f" {chi2:>7.2f} {p_chi2:>7.3f}"
        )


if __name__ == "__main__":
    main()
