"""Live fleet missions against the Monte-Carlo engine on the same profile: do the T_nc agree?

    .venv/bin/python benchmarks/companion_live_vs_batch.py --live 45 --batch 2000 --duration 300

Runs ``--live`` full fleet missions (emulator + one companion process per vehicle, seeds
FIRST..FIRST+N-1, one fleet at a time) and ``--batch`` missions of
mdm_montecarlo.engines.engine.run_block with the same profile, mission duration and start rule, then
two-sided Mann-Whitney U and Kolmogorov-Smirnov tests of the T_nc samples at 5 % (T_nc is a
small integer: the KS p-value is conservative with ties). Live T_nc counts each vehicle's
confirmations within ``--duration`` of its own search start (takeoff excluded), as the batch
counts from t = 0. A seed whose results.json exists under --out is read, not flown again, so
a study can be extended or resumed.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from scipy import stats

from mdm_core.metrics import confirmed_within, team_times
from mdm_ground.fleet.runner import FleetOptions, run_fleet
from mdm_montecarlo.engines.engine import run_block
from mdm_profiles import load_profile


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--profile", default="paper-fixed")
    p.add_argument("--live", type=int, default=8)
    p.add_argument("--first-seed", type=int, default=1)
    p.add_argument("--batch", type=int, default=400)
    p.add_argument("--duration", type=float, default=300.0)
    p.add_argument("--speedup", type=float, default=100.0)
    p.add_argument("--lockstep", action="store_true", help="FleetOptions(lockstep=True)")
    p.add_argument("--base-port", type=int, default=36540)
    p.add_argument("--out", type=Path, default=Path("runs/live-vs-batch"))
    args = p.parse_args()

    profile = load_profile(args.profile)
    short = profile.model_copy(
        update={
            "mission": profile.mission.model_copy(
                update={"duration": args.duration, "ts_cap": args.duration}
            )
        }
    )
    started = time.perf_counter()
    res = run_block(short, seed=12345, block=0, n_runs=args.batch)
    batch = confirmed_within(team_times(res.per_vehicle), args.duration).astype(float)
    print(
        f"batch: {args.batch} runs in {time.perf_counter() - started:.1f} s, "
        f"mean T_nc {batch.mean():.3f}"
    )

    live: list[float] = []
    for seed in range(args.first_seed, args.first_seed + args.live):
        done = args.out / f"seed-{seed}" / "results.json"
        if done.exists():
            r = json.loads(done.read_text())
            tnc, false, reasons = r["tnc"], r["false_confirmations"], r["end_reasons"].values()
        else:
            fleet = run_fleet(
                FleetOptions(
                    profile=args.profile,
                    out=args.out / f"seed-{seed}",
                    speedup=args.speedup,
                    duration=args.duration,
                    seed=seed,
                    base_port=args.base_port,
                    lockstep=args.lockstep,
                )
            )
            tnc, false = fleet.tnc, fleet.false_confirmations
            reasons = fleet.end_reasons.values()
        live.append(float(tnc))
        print(
            f"live seed {seed}: T_nc {tnc}, false confirmations {false}, "
            f"ends {sorted(set(reasons))}",
            flush=True,
        )
    u = stats.mannwhitneyu(live, batch, alternative="two-sided")
    ks = stats.ks_2samp(live, batch)
    out = {
        "profile": args.profile,
        "duration": args.duration,
        "n_live": len(live),
        "n_batch": len(batch),
        "mean_live": float(np.mean(live)),
        "mean_batch": float(batch.mean()),
        "live": live,
        "mannwhitney_u": float(u.statistic),
        "mannwhitney_p": float(u.pvalue),
        "ks_d": float(ks.statistic),
        "ks_p": float(ks.pvalue),
        "batch_distribution": np.bincount(batch.astype(int)).tolist(),
        "live_distribution": np.bincount(np.array(live, dtype=int)).tolist(),
        "agree_at_5pct": bool(u.pvalue > 0.05 and ks.pvalue > 0.05),
    }
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "summary.json").write_text(json.dumps(out, indent=2))
    print(json.dumps(out))


if __name__ == "__main__":
    main()
