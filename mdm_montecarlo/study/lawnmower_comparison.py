"""MDM against the searches without talk: the comparison table of docs/model.md, "The lawnmower
baseline" (T_nc and T_S of MDM, US, LS and both lawnmowers, each scenario, 6/12/24 vehicles).

    .venv/bin/python -m mdm_montecarlo.study.lawnmower_comparison --runs 1000 --seed 2024

Prints a Markdown table: mean and std of T_nc and T_S, T_S's 10/50/90 % quantiles (capped
runs count as the cap) and the runs capped.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence

import numpy as np

from mdm_montecarlo.engines.runner import run_many
from mdm_montecarlo.study.variants import with_fleet_size, with_method
from mdm_profiles import MissionProfile, builtin_profile
from mdm_profiles.overrides import apply_overrides

SCENARIOS = {
    "fixed": "paper-fixed",
    "pop-up": "paper-popup",
    "dynamic": "paper-dynamic",
    "false": "paper-fixed-false",
}
METHODS = {
    "MDM": ("MDM", ()),
    "US": ("US", ()),
    "LS": ("LS", ()),
    "LM1": ("LM1", ()),
    "LM2 (spiral in)": ("LM2", ()),
    "LM2 (spiral out)": ("LM2", ("policy.lawnmower.search=spiral_out",)),
}


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=2024)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--vehicles", default="6,12,24", help="team sizes, comma-separated")
    args = parser.parse_args(argv)
    sizes = [int(v) for v in args.vehicles.split(",")]
    cases: list[tuple[str, int, str, MissionProfile]] = []
    for scenario, name in SCENARIOS.items():
        for n in sizes:
            for label, (method, settings) in METHODS.items():
                profile = apply_overrides(
                    with_fleet_size(with_method(builtin_profile(name), method), n), list(settings)
                )
                cases.append((scenario, n, label, profile))
    results = run_many([c[3] for c in cases], runs=args.runs, seed=args.seed, workers=args.workers)
    print("| scenario | UAVs | method | T_nc | T_S (s) | T_S 10/50/90 % (s) | capped |")
    print("|---|---|---|---|---|---|---|")
    for (scenario, n, label, _), result in zip(cases, results, strict=True):
        tnc = result.tnc
        ts, capped = result.ts()
        q = np.quantile(ts, [0.1, 0.5, 0.9])
        print(
            f"| {scenario} | {n} | {label} | {tnc.mean():.2f} ± {tnc.std():.2f} | "
            f"{ts.mean():.0f} ± {ts.std():.0f} | {q[0]:.0f} / {q[1]:.0f} / {q[2]:.0f} | "
            f"{int(capped.sum())} |"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
