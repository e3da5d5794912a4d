"""Write a run's map (GeoJSON and PNG) into its run directory."""

from __future__ import annotations

import json
import logging
from pathlib import Path

from mdm_ground.run_map.geojson import run_geojson
from mdm_ground.run_map.png import draw_png
from mdm_ground.run_map.tracks import read_tracks
from mdm_profiles import MissionProfile

log = logging.getLogger(__name__)


def write_run_map(
    log_dir: Path, profile: MissionProfile, vehicles: list[int], stem: str = "map"
) -> tuple[Path, Path]:
    """``log_dir/<stem>.geojson`` and ``log_dir/<stem>.png`` from the mission logs of
    ``vehicles``; returns both paths."""
    tracks = read_tracks(log_dir, vehicles)
    geojson = log_dir / f"{stem}.geojson"
    geojson.write_text(json.dumps(run_geojson(profile, tracks), indent=1), encoding="utf-8")
    png = log_dir / f"{stem}.png"
    found = sum(len(t.confirmations) for t in tracks)
    who = f"vehicle {vehicles[0]}" if len(vehicles) == 1 else f"{len(vehicles)} vehicles"
    draw_png(
        profile, tracks, png, f"{profile.name}: {who}, {found} confirmation(s) ({log_dir.name})"
    )
    log.info("run map: %s, %s", geojson, png)
    return geojson, png
