"""`companion map`: (re)build a run directory's map from its mission logs."""

from __future__ import annotations

import argparse
import logging
import re
from pathlib import Path

from companion.run_map.writer import write_run_map
from mdm_profiles import MissionProfile, load_profile

log = logging.getLogger(__name__)
_LOG_NAME = re.compile(r"mission-(\d+)\.jsonl")


def add_map_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Register `companion map`."""
    p = sub.add_parser("map", help="write map.geojson and map.png of a run directory")
    p.add_argument("--profile", required=True, help="the profile the run flew")
    p.add_argument("--log-dir", type=Path, required=True, help="run directory (mission-I.jsonl)")


def logged_vehicles(log_dir: Path) -> list[int]:
    """Vehicle indices with a mission log in ``log_dir``, in order."""
    found = (_LOG_NAME.fullmatch(p.name) for p in log_dir.glob("mission-*.jsonl"))
    return sorted(int(m.group(1)) for m in found if m is not None)


def map_command(args: argparse.Namespace) -> int:
    """`companion map`: every vehicle logged in the directory on one map."""
    vehicles = logged_vehicles(args.log_dir)
    if not vehicles:
        raise ValueError(f"--log-dir {args.log_dir}: no mission-I.jsonl in it")
    geojson, png = write_run_map(args.log_dir, load_profile(args.profile), vehicles)
    print(f"map: {geojson} {png}")
    return 0


def map_after_run(log_dir: Path, profile: MissionProfile, vehicles: list[int], stem: str) -> None:
    """The map at the end of a live run; a map that cannot be drawn is an error line, and the
    mission's own result stands (it flew, its logs are on disk, `companion map` retries)."""
    try:
        geojson, png = write_run_map(log_dir, profile, vehicles, stem)
    except (OSError, ValueError, RuntimeError) as exc:
        log.error("run map not written in %s: %s", log_dir, exc)
        return
    print(f"map: {geojson} {png}", flush=True)
