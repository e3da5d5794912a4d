"""`mdm-montecarlo plan --profile SITE --teams 2,4,6 --endurance MIN --methods MDM,LM2 --want 0.9`:
how many vehicles for this site (mdm_montecarlo.study.team_plan): a table, plan.csv and plan.png."""

from __future__ import annotations

import argparse
import csv
import sys
import time
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path

from mdm_montecarlo.commands.result_files import check_writable
from mdm_montecarlo.engines.runner import run_many
from mdm_montecarlo.study.team_plan import (
    PlanAsk,
    PlanRow,
    check,
    format_plan,
    plan_row,
    profiles,
    smallest_teams,
)
from mdm_profiles import load_profile
from mdm_profiles.overrides import apply_overrides


def _numbers(text: str) -> tuple[int, ...]:
    try:
        return tuple(int(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected integers like 2,4,6, got {text!r}") from None


def add_plan_parser(
    sub: argparse._SubParsersAction[argparse.ArgumentParser],
    common: Callable[[argparse.ArgumentParser], None],
) -> None:
    p = sub.add_parser(
        "plan", help="how many vehicles for a site: P(every target confirmed) by team size"
    )
    p.add_argument("--profile", required=True, help="field profile (with site.geofence)")
    p.add_argument("--teams", type=_numbers, required=True, help="team sizes, e.g. 2,4,6,8")
    p.add_argument(
        "--endurance", type=float, required=True, help="minutes of search per battery pack"
    )
    p.add_argument(
        "--methods", default="MDM,US,LM1,LM2", help="comma-separated (default MDM,US,LM1,LM2)"
    )
    p.add_argument("--want", type=float, default=0.9, help="probability to reach (default 0.9)")
    p.add_argument("--out", help="folder for plan.csv and plan.png (default reports/plan-<time>)")
    common(p)


def plan_command(args: argparse.Namespace) -> int:
    profile = apply_overrides(load_profile(args.profile), args.set)
    methods = tuple(m.strip() for m in args.methods.split(",") if m.strip())
    ask = PlanAsk(profile, args.teams, args.endurance, methods, args.want)
    check(ask)
    out = Path(args.out or time.strftime("reports/plan-%Y%m%d-%H%M%S", time.gmtime()))
    check_writable(out)
    configs = profiles(ask)
    start = time.perf_counter()
    results = run_many(
        [c[2] for c in configs],
        runs=args.runs,
        seed=args.seed,
        workers=args.workers or 2,
        scheduler=args.scheduler,
    )
    wall = time.perf_counter() - start
    rows = [plan_row(m, n, r) for (m, n, _), r in zip(configs, results, strict=True)]
    print(format_plan(rows, ask))
    _write_csv(out / "plan.csv", rows)
    _plot(out / "plan.png", rows, ask)
    print(
        f"{len(configs)} configurations x {args.runs} runs in {wall:.1f} s; "
        f"plan.csv and plan.png in {out}",
        file=sys.stderr,
    )
    return 0


def _write_csv(path: Path, rows: list[PlanRow]) -> None:
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(asdict(rows[0])))
        writer.writeheader()
        writer.writerows(asdict(r) for r in rows)


def _plot(path: Path, rows: list[PlanRow], ask: PlanAsk) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 7), sharex=True)
    best = smallest_teams(rows, ask.want)
    for method in ask.methods:
        mine = sorted((r for r in rows if r.method == method), key=lambda r: r.vehicles)
        n = [r.vehicles for r in mine]
        smallest = best.get(method)
        label = f"{method} (>= {ask.want:g} from {smallest})" if smallest else method
        top.errorbar(
            n,
            [r.p_all for r in mine],
            yerr=[2 * r.p_all_se for r in mine],
            marker="o",
            capsize=3,
            label=label,
        )
        bottom.plot(n, [r.expected for r in mine], marker="o", label=method)
    real = sum(not t.false_target for t in ask.profile.targets)
    top.axhline(ask.want, color="grey", linestyle="--", linewidth=1, label=f"want {ask.want:g}")
    top.set_ylabel("P(every real target confirmed)")
    top.set_ylim(-0.03, 1.03)
    top.set_title(f"{ask.profile.name}: {ask.endurance_min:g} min of search per pack (±2 s.e.)")
    top.legend(fontsize=8)
    bottom.axhline(real, color="grey", linestyle=":", linewidth=1, label=f"{real} real targets")
    bottom.set_ylabel("expected real targets confirmed")
    bottom.set_xlabel("vehicles")
    bottom.legend(fontsize=8)
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
