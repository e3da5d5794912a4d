"""`companion map`: (re)build a run directory's map from its mission logs."""

from __future__ import annotations

import argparse
import json
import logging
import re
from pathlib import Path

from mdm_ground.live_web.cli_args import add_tiles_argument
from mdm_ground.run_map.writer import write_run_map
from mdm_profiles import MissionProfile, load_profile

log = logging.getLogger(__name__)
_LOG_NAME = re.compile(r"mission-(\d+)\.jsonl")


def add_map_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Register `companion map`."""
    p = sub.add_parser("map", help="write map.geojson and map.png of a run directory")
    p.add_argument(
        "--profile",
        help="the profile the run flew (with --web: default the one its run.json names)",
    )
    p.add_argument("--log-dir", type=Path, help="run directory (mission-I.jsonl)")
    p.add_argument(
        "--web",
        type=Path,
        metavar="RUN_DIR",
        help="instead: replay the run on the live page, with a time slider",
    )
    p.add_argument(
        "--web-bind",
        default="127.0.0.1:8765",
        metavar="[HOST:]PORT",
        help="where --web serves the page (port 0: any free)",
    )
    add_tiles_argument(p)


def logged_vehicles(log_dir: Path) -> list[int]:
    """Vehicle indices with a mission log in ``log_dir``, in order."""
    found = (_LOG_NAME.fullmatch(p.name) for p in log_dir.glob("mission-*.jsonl"))
    return sorted(int(m.group(1)) for m in found if m is not None)


def map_command(args: argparse.Namespace) -> int:
    """`companion map`: every vehicle logged in the directory on one map (or, --web, the
    run replayed on the live page)."""
    if args.web is not None:
        from mdm_ground.live_web.commands import replay_command

        return replay_command(
            args.web,
            load_profile(args.profile or _run_profile(args.web)),
            args.web_bind,
            args.web_tiles,
        )
    if args.profile is None or args.log_dir is None:
        raise ValueError("companion map needs --profile and --log-dir (or --web RUN_DIR)")
    vehicles = logged_vehicles(args.log_dir)
    if not vehicles:
        raise ValueError(f"--log-dir {args.log_dir}: no mission-I.jsonl in it")
    geojson, png = write_run_map(args.log_dir, load_profile(args.profile), vehicles)
    print(f"map: {geojson} {png}")
    return 0


def _run_profile(run_dir: Path) -> str:
    """The profile a run directory's run.json names (as given to the fleet)."""
    path = run_dir / "run.json"
    try:
        run = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"--web {run_dir}: no readable run.json ({exc}); give --profile") from None
    name = run.get("profile_arg") or run.get("profile") if isinstance(run, dict) else None
    if not isinstance(name, str):
        raise ValueError(f"{path}: names no profile; give --profile")
    return name


def map_after_run(log_dir: Path, profile: MissionProfile, vehicles: list[int], stem: str) -> None:
    """The map at the end of a live run; a map that cannot be drawn is an error line, and the
    mission's own result stands (it flew, its logs are on disk, `companion map` retries)."""
    try:
        geojson, png = write_run_map(log_dir, profile, vehicles, stem)
    except (OSError, ValueError, RuntimeError) as exc:
        log.error("run map not written in %s: %s", log_dir, exc)
        return
    print(f"map: {geojson} {png}", flush=True)
