"""Live fleet missions against the Monte-Carlo engine on the same profile: do the T_nc agree?

    .venv/bin/python benchmarks/companion_live_vs_batch.py --live 8 --batch 400 --duration 300

Runs ``--live`` full fleet missions (emulator + one companion process per vehicle, seeds
1..N) and ``--batch`` missions of mdm_montecarlo.engine.run_block, then a two-sided
Mann-Whitney U test of the T_nc samples (T_nc is a small integer, so rank-based) at 5 %.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from scipy import stats

from companion.fleet.runner import FleetOptions, run_fleet
from mdm_montecarlo.engine import run_block
from mdm_montecarlo.metrics import confirmed_within, team_times
from mdm_profiles import load_profile


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--profile", default="paper-fixed")
    p.add_argument("--live", type=int, default=8)
    p.add_argument("--batch", type=int, default=400)
    p.add_argument("--duration", type=float, default=300.0)
    p.add_argument("--speedup", type=float, default=100.0)
    p.add_argument("--base-port", type=int, default=36540)
    p.add_argument("--out", type=Path, default=Path("runs/live-vs-batch"))
    args = p.parse_args()

    profile = load_profile(args.profile)
    short = profile.model_copy(
        update={"mission": profile.mission.model_copy(update={"duration": args.duration,
                                                                "ts_cap": args.duration})}
    )  # fmt: skip
    started = time.perf_counter()
    res = run_block(short, seed=12345, block=0, n_runs=args.batch)
    batch = confirmed_within(team_times(res.per_vehicle), args.duration).astype(float)
    print(f"batch: {args.batch} runs in {time.perf_counter() - started:.1f} s, "
          f"mean T_nc {batch.mean():.3f}")  # fmt: skip

    live: list[float] = []
    for seed in range(1, args.live + 1):
        r = run_fleet(FleetOptions(profile=args.profile, out=args.out / f"seed-{seed}",
                                   speedup=args.speedup, duration=args.duration, seed=seed,
                                   base_port=args.base_port))  # fmt: skip
        live.append(float(r.tnc))
        print(f"live seed {seed}: T_nc {r.tnc}, false confirmations {r.false_confirmations}",
              flush=True)  # fmt: skip
    u = stats.mannwhitneyu(live, batch, alternative="two-sided")
    ks = stats.ks_2samp(live, batch)
    out = {
        "profile": args.profile, "duration": args.duration,
        "n_live": len(live), "n_batch": len(batch),
        "mean_live": float(np.mean(live)), "mean_batch": float(batch.mean()),
        "live": live, "mannwhitney_u": float(u.statistic), "mannwhitney_p": float(u.pvalue),
        "ks_d": float(ks.statistic), "ks_p": float(ks.pvalue),
        "agree_at_5pct": bool(u.pvalue > 0.05),
    }  # fmt: skip
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "summary.json").write_text(json.dumps(out, indent=2))
    print(json.dumps(out))


if __name__ == "__main__":
    main()
