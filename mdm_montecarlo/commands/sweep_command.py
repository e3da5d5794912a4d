"""`mdm-montecarlo sweep --profile P [--method M] --vary KEY=V1,V2,... [--vary ...]`: every
combination of the values (sweep.py), a combined table (results.csv, report.md), one plot
per metric with its confidence band, the samples of every run, and the provenance."""

from __future__ import annotations

import argparse
import json
import os
import signal
import sys
import time
from collections.abc import Callable
from pathlib import Path
from types import FrameType

from tqdm import tqdm

from mdm_montecarlo.commands.result_files import PROVENANCE_FILE, append_provenance, check_writable
from mdm_montecarlo.study.readings import reading_named, scenario_of
from mdm_montecarlo.study.samples import RUNS, write_tables
from mdm_montecarlo.study.sweep import (
    SweepAsk,
    combined,
    done,
    open_folder,
    parse_vary,
    points,
    run_points,
)
from mdm_montecarlo.study.sweep_table import format_rows, point_rows, write_csv
from mdm_profiles import load_profile
from mdm_provenance import collect

INTERRUPTED = 130


def add_sweep_parser(
    sub: argparse._SubParsersAction[argparse.ArgumentParser],
    common: Callable[[argparse.ArgumentParser], None],
    reading_flag: Callable[[argparse.ArgumentParser], None],
) -> None:
    """The `sweep` subcommand; ``common`` and ``reading_flag`` add the options it shares with
    `run`."""
    p = sub.add_parser(
        "sweep", help="one profile over the cartesian product of field values", description=__doc__
    )
    p.add_argument("--profile", required=True, help="profile file or built-in name")
    p.add_argument(
        "--method",
        help="US, BS, LS, PSO, SPSO, ARPSO, LM1, LM2, MDM (the profile's levels) or MDM:L1+L2 "
        "(default: the profile's policy)",
    )
    p.add_argument(
        "--vary",
        action="append",
        default=[],
        required=True,
        metavar="PATH=V1,V2,...",
        help="a profile field as in --set and its values (repeatable: the cartesian product)",
    )
    p.add_argument(
        "--out",
        help="sweep folder (default reports/sweep-<profile>); the same command again resumes it",
    )
    reading_flag(p)
    common(p)


class _CtrlC:
    """SIGINT's handler during the runs: KeyboardInterrupt as by default, and remembered, for
    sweep.run_points to find where Python dropped the exception."""

    def __init__(self) -> None:
        self.seen = False

    def __call__(self, signum: int, frame: FrameType | None) -> None:
        self.seen = True
        raise KeyboardInterrupt


def sweep_command(args: argparse.Namespace) -> int:
    base = load_profile(args.profile)
    reading = reading_named(args.reading)
    ask = SweepAsk(
        profile=args.profile,
        method=args.method,
        overrides=[*reading.overrides(scenario_of(base)), *args.set],
        vary=parse_vary(args.vary),
        runs=args.runs,
        seed=args.seed,
    )
    every = points(base, ask)  # every point validated before any run
    folder = Path(args.out or f"reports/sweep-{base.name}")
    check_writable(folder)
    open_folder(folder, ask)
    todo = [p for p in every if not done(folder, p.index)]
    if len(todo) < len(every):
        print(
            f"mdm-montecarlo: resuming {folder}: {len(every) - len(todo)} of {len(every)} "
            "points already done",
            file=sys.stderr,
        )
    bar = tqdm(
        total=len(todo) * args.runs,
        unit="run",
        desc="sweep",
        disable=args.no_progress or args.json,
        file=sys.stderr,
    )
    workers = args.workers or os.cpu_count() or 1
    ctrl_c = _CtrlC()
    previous = signal.getsignal(signal.SIGINT)
    if previous is signal.default_int_handler:  # not where Ctrl-C is ignored (cmd &)
        signal.signal(signal.SIGINT, ctrl_c)
    try:
        run_points(
            folder,
            ask,
            todo,
            workers=workers,
            scheduler=args.scheduler,
            progress=bar.update,
            interrupted=lambda: ctrl_c.seen,
        )
    except KeyboardInterrupt:
        bar.close()
        finished = sum(done(folder, p.index) for p in every)
        print(
            f"mdm-montecarlo: interrupted; {finished} of {len(every)} points done in {folder}; "
            "the same command goes on from there",
            file=sys.stderr,
        )
        return INTERRUPTED
    finally:
        if previous is signal.default_int_handler:
            signal.signal(signal.SIGINT, previous)
    bar.close()
    tables = combined(folder, every)
    rows = point_rows(ask, tables[RUNS])
    write_csv(folder / "results.csv", rows)
    from mdm_montecarlo.study.sweep_plots import plot_metric  # matplotlib: only once it is needed

    method = args.method or "the profile's policy"
    title = f"{base.name}, {method}: {args.runs} runs per point, seed {args.seed}"
    figures = ["tnc"] + (["ts"] if all(r.ts is not None for r in rows) else [])
    for metric in figures:
        plot_metric(str(folder / f"sweep-{metric}.png"), ask, rows, metric, title)
    report = folder / "report.md"
    lines = [
        f"# Sweep of {base.name}, {method}",
        "",
        f"{args.runs} runs per point, seed {args.seed} (the same for every point), "
        f"{len(every)} points."
        + (f" Overrides: {', '.join(args.set)}." if args.set else "")
        + (
            f" Resumed: {len(every) - len(todo)} points from an earlier start."
            if len(todo) < len(every)
            else ""
        ),
        "",
        format_rows(ask, rows),
        "",
        *(f"![{metric}](sweep-{metric}.png)\n" for metric in figures),
    ]
    report.write_text("\n".join(lines), encoding="utf-8")
    record = collect(seed=args.seed, started=args.started, command_line=args.command_line)
    write_tables(folder, tables, record.as_dict())
    (folder / PROVENANCE_FILE).write_text(json.dumps(record.as_dict(), indent=2) + "\n")
    append_provenance(report, record)
    if args.json:
        for row in rows:
            print(json.dumps(row.as_dict()))
    else:
        print(format_rows(ask, rows))
        print(f"\nsweep: {report} ({time.perf_counter() - args.started:.1f} s)", file=sys.stderr)
    return 0
