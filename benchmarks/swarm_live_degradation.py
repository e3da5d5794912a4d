"""Live PSO under message loss and delay, beside the Monte-Carlo engine on the same profile.

Live: ``companion fleet --json --mqtt 127.0.0.1 ...`` (emulator + one companion per vehicle,
bests shared through the broker, the delay/drop knob applied by each receiver), ``--seeds``
runs per setting, one fleet at a time. Engine: mdm_montecarlo.engines.runner.run_missions, ``--runs``
missions per setting (what ``mdm-montecarlo run --profile FILE --method PSO --set
policy.swarm.message_drop=P`` runs; its ``tnc_mean`` is the T_nc column here).

The profile is the built-in swarm-small, also flown by tests/companion/test_swarm_live.py (2.5 km square, one real target in
the middle, one false target, 3 UAVs, 900 m signal, 400 s). Printed per setting: mean T_nc,
how many runs confirmed the real target, the mean time (search seconds) to its first
confirmation over the runs that confirmed it (± standard deviation), and for live runs the mean
number of iterations per vehicle that followed a peer's best. The engine is also run on the profile without the false
target (its signal sensor reads false targets, the live confirmation sensor does not: see
docs/model.md).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from companion.telemetry import read_records
from mdm_montecarlo.engines.runner import run_missions
from mdm_profiles import MissionProfile, builtin_profile, write_profile
from mdm_profiles.overrides import apply_overrides

SETTINGS = ((0.0, 0.0), (0.5, 0.0), (1.0, 0.0), (0.0, 30.0))
"""(message_drop, message_delay s)."""


@dataclass
class Row:
    tnc: float
    confirmed: int
    runs: int
    ts: float
    """Mean time to the real target's first confirmation, over the runs that confirmed it."""
    ts_sd: float
    """Its standard deviation over those runs."""
    followed: float = math.nan
    """Live: mean iterations per vehicle that followed a peer's best."""


def _sets(drop: float, delay: float) -> list[str]:
    return [f"policy.swarm.message_drop={drop}", f"policy.swarm.message_delay={delay}"]


def engine(
    base: MissionProfile, drop: float, delay: float, runs: int, seed: int, workers: int
) -> Row:
    profile = apply_overrides(base, _sets(drop, delay))
    result = run_missions(profile, runs=runs, seed=seed, workers=workers)
    real = result.team_times[:, result.real].min(axis=1)
    hit = real <= profile.mission.duration
    ts = float(real[hit].mean()) if hit.any() else math.nan
    sd = float(real[hit].std(ddof=1)) if hit.sum() > 1 else math.nan
    return Row(float(result.tnc.mean()), int(hit.sum()), runs, ts, sd)


def live(base: MissionProfile, drop: float, delay: float, seeds: list[int], speedup: float) -> Row:
    tnc: list[int] = []
    times: list[float] = []
    followed: list[int] = []
    with tempfile.TemporaryDirectory(prefix="swarm-live-") as tmp:
        knob = Path(tmp) / "profile.yaml"
        write_profile(apply_overrides(base, _sets(drop, delay)), knob)
        for seed in seeds:
            out = Path(tmp) / f"run-{seed}"
            cmd = [str(Path(sys.executable).parent / "companion"), "fleet", "--profile", str(knob), "--json",
                   "--quiet", "--mqtt", "127.0.0.1", "--mqtt-prefix",
                   f"mdm/bench-{os.getpid()}-{drop}-{delay}-{seed}", "--speedup", str(speedup),
                   "--duration", "400", "--seed", str(seed), "--out", str(out)]  # fmt: skip
            done = subprocess.run(cmd, capture_output=True, text=True, check=True)
            result = json.loads(done.stdout.strip().splitlines()[-1])
            tnc.append(int(result["tnc"]))
            first = result["first_confirmation"][0]
            if first is not None:
                times.append(float(first))
            for log in sorted(out.glob("mission-*.jsonl")):
                followed += [
                    int(r["peer_bests_used"]) for r in read_records(log) if r["event"] == "swarm"
                ]
    ts = statistics.fmean(times) if times else math.nan
    sd = statistics.stdev(times) if len(times) > 1 else math.nan
    return Row(statistics.fmean(tnc), len(times), len(seeds), ts, sd, statistics.fmean(followed))


def _fmt(row: Row) -> str:
    ts = "-" if math.isnan(row.ts) else f"{row.ts:5.1f} ± {row.ts_sd:4.1f}"
    followed = "" if math.isnan(row.followed) else f"{row.followed:9.1f}"
    return f"{row.tnc:6.3f} {row.confirmed:5d}/{row.runs:<5d} {ts:>12} {followed}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=6, help="live runs per setting (seeds 1..N)")
    ap.add_argument("--runs", type=int, default=1000, help="engine runs per setting")
    ap.add_argument("--seed", type=int, default=2024, help="engine master seed")
    ap.add_argument("--workers", type=int, default=2, help="engine worker processes")
    ap.add_argument("--speedup", type=float, default=50.0, help="live sim s per wall s")
    ap.add_argument("--no-live", action="store_true", help="engine only")
    ap.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="PATH=VALUE",
        help="override a field of swarm-small, e.g. policy.swarm.signal_radius=null (the "
        "detection sensor's radius, the default of other profiles)",
    )
    args = ap.parse_args()
    seeds = list(range(1, args.seeds + 1))
    profile = apply_overrides(builtin_profile("swarm-small"), args.set)
    real = [t for t in profile.targets if not t.false_target]
    no_false = profile.model_copy(update={"targets": real})
    print(
        f"PSO, 3 UAVs, 2.5 km square, 400 s; live {len(seeds)} seeds at {args.speedup:g}x, "
        f"engine {args.runs} runs seed {args.seed}; overrides: {args.set or 'none'}"
    )
    head = f"{'T_nc':>6} {'conf/runs':<11} {'ts s ± sd':>12}"
    print(f"{'drop':>4} {'delay':>5} | live {head} {'followed':>9} | engine {head} "
          f"| engine, no false target {head}")  # fmt: skip
    for drop, delay in SETTINGS:
        started = time.monotonic()
        e = engine(profile, drop, delay, args.runs, args.seed, args.workers)
        e_nf = engine(no_false, drop, delay, args.runs, args.seed, args.workers)
        lv = "-" if args.no_live else _fmt(live(profile, drop, delay, seeds, args.speedup))
        print(f"{drop:4.1f} {delay:5.0f} | live {lv} | engine {_fmt(e)} "
              f"| engine, no false target {_fmt(e_nf)}   ({time.monotonic() - started:.0f} s)",
              flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
