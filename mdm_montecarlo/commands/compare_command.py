"""`mdm-montecarlo compare A B`: each of A and B a results folder (`run`, `reproduce` or
`sweep` output, ``FOLDER#CONFIG`` where it holds several configurations) or a configuration
``PROFILE[:METHOD]`` simulated here; prints compare.py's statistics of B against A."""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from mdm_montecarlo.engines.runner import run_missions
from mdm_montecarlo.study.compare import compare_samples, format_comparisons
from mdm_montecarlo.study.samples import read_runs, run_outcomes
from mdm_montecarlo.study.variants import with_method
from mdm_profiles import load_profile
from mdm_profiles.overrides import apply_overrides

METRICS = ("T_nc", "T_S")


@dataclass(frozen=True)
class Sample:
    """One side of a comparison: its label and its per-run values (T_S None if not simulated)."""

    label: str
    tnc: NDArray[np.float64]
    ts: NDArray[np.float64] | None


def add_compare_parser(
    sub: argparse._SubParsersAction[argparse.ArgumentParser],
    common: Callable[[argparse.ArgumentParser], None],
) -> None:
    """The `compare` subcommand; ``common`` adds the options it shares with `run`."""
    p = sub.add_parser(
        "compare",
        help="B against A: difference of means with its CI, Mann-Whitney U, bootstrap, effect size",
        description=__doc__,
    )
    p.add_argument("a", help="results folder (FOLDER or FOLDER#CONFIG) or PROFILE[:METHOD]")
    p.add_argument("b", help="the same for B")
    p.add_argument(
        "--seed-b",
        type=int,
        help="seed of configuration B (default: --seed + 1, so the samples are independent)",
    )
    p.add_argument(
        "--bootstrap", type=int, default=10_000, help="bootstrap resamples (default 10000)"
    )
    common(p)


def _from_folder(spec: str) -> Sample:
    folder, _, config = spec.partition("#")
    table = read_runs(Path(folder)).to_pydict()
    configs = list(dict.fromkeys(table["config"]))
    if not config:
        if len(configs) != 1:
            raise ValueError(
                f"{folder} holds {len(configs)} configurations; name one as "
                f"{folder}#CONFIG, CONFIG one of:\n  " + "\n  ".join(configs)
            )
        config = configs[0]
    if config not in configs:
        raise ValueError(f"{folder}: no configuration {config!r}")
    mine = np.array(table["config"]) == config
    tnc = np.array(table["tnc"], dtype=float)[mine]
    has_ts = bool(np.array(table["has_ts"])[mine].all())
    ts = np.array(table["ts_s"], dtype=float)[mine] if has_ts else None
    return Sample(f"{folder} [{config}]", tnc, ts)


def _simulated(spec: str, seed: int, args: argparse.Namespace) -> Sample:
    name, _, method = spec.partition(":")
    profile = apply_overrides(load_profile(name), args.set)
    if method:
        profile = with_method(profile, method)
    res = run_missions(
        profile,
        runs=args.runs,
        seed=seed,
        workers=args.workers or os.cpu_count() or 1,
        scheduler=args.scheduler,
    )
    out = run_outcomes(res)
    return Sample(f"{spec} (seed {seed}, {res.runs} runs)", out.tnc.astype(float), out.ts)


def _sample(spec: str, seed: int, args: argparse.Namespace) -> Sample:
    if Path(spec.partition("#")[0]).is_dir():
        return _from_folder(spec)
    return _simulated(spec, seed, args)


def _check(spec: str) -> None:
    """Refuse a spec that is neither a folder nor a profile before simulating either side."""
    if Path(spec.partition("#")[0]).is_dir():
        return
    name, _, method = spec.partition(":")
    profile = load_profile(name)
    if method:
        with_method(profile, method)


def compare_command(args: argparse.Namespace) -> int:
    if args.bootstrap < 100:
        raise ValueError(f"--bootstrap: at least 100 resamples, got {args.bootstrap}")
    for spec in (args.a, args.b):
        _check(spec)
    a = _sample(args.a, args.seed, args)
    b = _sample(args.b, args.seed + 1 if args.seed_b is None else args.seed_b, args)
    rows = [compare_samples("T_nc", a.tnc, b.tnc, resamples=args.bootstrap)]
    if a.ts is not None and b.ts is not None:
        rows.append(compare_samples("T_S", a.ts, b.ts, resamples=args.bootstrap))
    else:
        print("mdm-montecarlo: no T_S on one side (a swarm): T_nc only", file=sys.stderr)
    if args.json:
        for row in rows:
            print(json.dumps({"a": a.label, "b": b.label, **row.as_dict()}))
    else:
        print(format_comparisons(a.label, b.label, rows))
    return 0
