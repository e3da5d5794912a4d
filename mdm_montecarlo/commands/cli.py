"""`mdm-montecarlo`: run one profile, or reproduce the tables of the paper's section IV."""

from __future__ import annotations

import argparse
import atexit
import gc
import importlib
import json
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path

from tqdm import tqdm

from mdm_montecarlo.commands.compare_command import add_compare_parser, compare_command
from mdm_montecarlo.commands.plan_command import add_plan_parser, plan_command
from mdm_montecarlo.commands.result_files import (
    append_provenance,
    case_columns,
    check_writable,
    write_result_files,
)
from mdm_montecarlo.commands.sweep_command import add_sweep_parser, sweep_command
from mdm_montecarlo.engines.runner import MissionResults, RunInterruptedError, run_many
from mdm_montecarlo.study.cases import TABLES, Case, Row, study_rows
from mdm_montecarlo.study.readings import (
    add_reading_flag,
    reading_named,
    scenario_of,
    with_reading,
)
from mdm_montecarlo.study.tables import MeasuredRow, format_table, measured_rows
from mdm_montecarlo.study.variants import with_method
from mdm_profiles import MissionProfile, ProfileError, load_profile
from mdm_profiles.overrides import apply_overrides
from mdm_provenance import add_version_flag, collect, cpu_seconds

INTERRUPTED = 130
"""Exit status after Ctrl-C (128 + SIGINT, as a shell reports it)."""


def _at_least_one(text: str) -> int:
    """argparse type of --runs and --workers: an integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {value}")
    return value


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--runs",
        type=_at_least_one,
        default=1000,
        help="Monte-Carlo runs per row (default 1000, as the paper)",
    )
    p.add_argument(
        "--seed", type=int, default=2024, help="master seed (same seed -> identical tables)"
    )
    p.add_argument(
        "--workers",
        type=_at_least_one,
        default=None,
        help="local worker processes, >= 1 (default: all cores)",
    )
    p.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://10.0.0.5:8786")
    p.add_argument(
        "--json", action="store_true", help="print rows as JSON lines instead of a table"
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="PATH=VALUE",
        help="override a profile field (of every row's profile with reproduce), "
        "e.g. policy.levels.1.index.kappa=300 (repeatable)",
    )


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="mdm-montecarlo", description=__doc__)
    add_version_flag(parser)
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="one profile and policy: a table row")
    run.add_argument(
        "--profile", required=True, help="profile file or built-in name (paper-fixed, ...)"
    )
    run.add_argument(
        "--method",
        help="US, BS, LS, PSO, SPSO, ARPSO, LM1, LM2, MDM (the profile's levels) or MDM:L1+L2 "
        "(default: the profile's policy)",
    )
    run.add_argument(
        "--out",
        help="folder for results.csv, the per-run samples and provenance.json "
        "(default reports/run-<UTC date>-<time>)",
    )
    add_reading_flag(run)
    _common(run)
    rep = sub.add_parser("reproduce", help="every table of section IV beside the paper's numbers")
    rep.add_argument(
        "--tables", default=",".join(TABLES), help=f"comma-separated subset of {', '.join(TABLES)}"
    )
    rep.add_argument(
        "--out", default="reports/section-iv", help="report folder (default reports/section-iv)"
    )
    add_reading_flag(rep)
    _common(rep)
    add_compare_parser(sub, _common)
    add_sweep_parser(sub, _common, add_reading_flag)
    add_plan_parser(sub, _common)
    return parser


def _workers(n: int | None) -> int:
    return n if n is not None else (os.cpu_count() or 1)


def _simulate(
    profiles: list[MissionProfile],
    args: argparse.Namespace,
    label: str,
    meanwhile: Callable[[], object] | None = None,
) -> list[MissionResults]:
    """Run every profile with one progress bar over all their runs (``meanwhile``: run_many's)."""
    bar = tqdm(
        total=len(profiles) * args.runs,
        unit="run",
        desc=label,
        disable=args.no_progress or args.json,
        file=sys.stderr,
    )
    try:
        return run_many(
            profiles,
            runs=args.runs,
            seed=args.seed,
            workers=_workers(args.workers),
            scheduler=args.scheduler,
            progress=bar.update,
            meanwhile=meanwhile,
        )
    finally:
        bar.close()


def _emit(rows: list[MeasuredRow], as_json: bool) -> None:
    if as_json:
        for r in rows:
            print(json.dumps(r.as_dict()))
    else:
        print(format_table(rows))


def _run(args: argparse.Namespace) -> int:
    profile = apply_overrides(with_reading(load_profile(args.profile), args.reading), args.set)
    if args.method:
        profile = with_method(profile, args.method)
    out = Path(args.out or time.strftime("reports/run-%Y%m%d-%H%M%S", time.gmtime()))
    check_writable(out)
    start = time.perf_counter()
    try:
        res = _simulate([profile], args, profile.name)[0]
        note = ""
    except RunInterruptedError as stop:
        if not stop.partial and not stop.finished:
            print("mdm-montecarlo: interrupted before any block of runs finished", file=sys.stderr)
            return INTERRUPTED
        res = (stop.finished or stop.partial)[0]
        note = f"interrupted: PARTIAL row from the {res.runs} of {args.runs} runs that finished"
    pol = profile.policy
    names = [lv.distribution for lv in pol.levels]
    method = "MDM:" + "+".join(names) if pol.kind == "mdm" else names[0]
    if pol.kind not in ("mdm", "sss"):
        method = pol.kind.upper()
    case = Case(
        scenario_of(profile),
        method,
        pol.levels[0].step / profile.area.north * 100,
        profile.fleet.vehicles,
        sum(t.false_target for t in profile.targets),
    )
    rows = measured_rows([Row("run", case, None)], {case: res})
    _emit(rows, args.json)
    if note:
        print(f"mdm-montecarlo: {note}", file=sys.stderr)  # and no files: not a full row
        return INTERRUPTED
    from mdm_montecarlo.study.report import write_csv  # matplotlib's import: only once it is needed

    write_csv(out / "results.csv", rows)
    record = collect(seed=args.seed, started=args.started, command_line=args.command_line)
    write_result_files(out, [({**case_columns(case), "profile": profile.name}, res)], record)
    if not args.json:
        print(
            f"{res.runs} runs in {time.perf_counter() - start:.1f} s (seed {args.seed}); "
            f"results, samples and provenance in {out}",
            file=sys.stderr,
        )
    return 0


def _import_report() -> None:
    """The report's imports, which the simulation workers do not need: matplotlib and
    scipy.special (metrics.Summary's t quantile, the comparisons' normal and t tails), about
    0.7 CPU-s. Done while the workers run rather than before they
    are forked, where one core would wait idle for them, or in the report, where it would."""
    importlib.import_module("scipy.special")
    importlib.import_module("mdm_montecarlo.study.report")


def _reproduce(args: argparse.Namespace) -> int:
    reading = reading_named(args.reading)
    tables = tuple(t.strip() for t in args.tables.split(",") if t.strip())
    rows = study_rows(tables)
    cases = list(dict.fromkeys(r.case for r in rows))
    profiles = [apply_overrides(c.profile(), args.set) for c in cases]
    out = Path(args.out)
    check_writable(out)
    start = time.perf_counter()
    cpu_start = cpu_seconds()
    partial = ""
    try:
        results = dict(
            zip(cases, _simulate(profiles, args, "reproduce", _import_report), strict=True)
        )
    except RunInterruptedError as stop:
        # Rows whose runs all finished are kept; a row with only some blocks done is dropped
        # (its figures would be from fewer runs than the others).
        results = {cases[i]: res for i, res in stop.finished.items()}
        partial = f"{len(results)} of {len(cases)} configurations finished"
        rows = [r for r in rows if r.case in results]
    wall = time.perf_counter() - start
    cpu_simulated = cpu_seconds()
    if partial and not rows:
        print(f"mdm-montecarlo: interrupted; {partial}, no report written", file=sys.stderr)
        return INTERRUPTED
    measured = measured_rows(rows, results)
    changed = f" Overrides: {', '.join(args.set)}." if args.set else ""
    header = (
        f"{args.runs} runs per row, seed {args.seed}, {len(cases)} configurations, "
        f"{wall:.1f} s wall time, reading {reading.name}. Paper numbers from "
        f"data/paper_tables.csv.{changed}"
    )
    if partial:
        header = f"**PARTIAL REPORT: interrupted (Ctrl-C); {partial}.** " + header
    from mdm_montecarlo.study.report import write_report  # see _import_report

    # The record is taken before the figures: the samples written beside them carry it.
    record = collect(seed=args.seed, started=args.started, command_line=args.command_line)
    configs = [(case_columns(c), res) for c, res in results.items()]
    path = write_report(
        out,
        rows,
        measured,
        results,
        header,
        workers=_workers(args.workers),
        meanwhile=lambda: write_result_files(out, configs, record),
        reading=reading.name,
    )
    append_provenance(path, record)
    if partial:
        print(f"mdm-montecarlo: interrupted; {partial}, partial report: {path}", file=sys.stderr)
        return INTERRUPTED
    _emit(measured, args.json)
    if not args.json:
        print(f"\nreport: {path} ({wall:.1f} s)", file=sys.stderr)
    # Where the time went (benchmarks/reproduce_wall.py reads this line): start-up is the
    # imports and the validated profiles, before the first run (the report's imports run
    # with the simulation and count in its CPU).
    print(
        f"phases: start-up {cpu_start:.1f} CPU-s; simulation {wall:.1f} s wall, "
        f"{cpu_simulated - cpu_start:.1f} CPU-s; report "
        f"{time.perf_counter() - start - wall:.1f} s wall, "
        f"{cpu_seconds() - cpu_simulated:.1f} CPU-s",
        file=sys.stderr,
    )
    return 0


def main(argv: list[str] | None = None) -> int:
    # At exit nothing needs collecting: frozen, the objects of numba, scipy and matplotlib are
    # not walked by the collector passes of the interpreter's shutdown (~0.3 s of the end).
    atexit.register(gc.freeze)
    args = _parser().parse_args(argv)
    args.started = time.perf_counter()  # the provenance's wall time counts from here
    args.command_line = sys.argv if argv is None else ["mdm-montecarlo", *argv]
    try:
        commands = {
            "run": _run,
            "reproduce": _reproduce,
            "compare": compare_command,
            "sweep": sweep_command,
            "plan": plan_command,
        }
        return commands[args.command](args)
    except (ProfileError, ValueError) as exc:
        print(f"mdm-montecarlo: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        # Outside the simulation (loading profiles, drawing the report): nothing to keep.
        print("mdm-montecarlo: interrupted", file=sys.stderr)
        return INTERRUPTED


if __name__ == "__main__":
    raise SystemExit(main())
