"""The arguments of `companion profile import` and `companion profile export` (the commands:
commands.py, imported only when one runs)."""

from __future__ import annotations

import argparse
from pathlib import Path

from mdm_ground.site_files.formats import FIRMWARE_TYPES, SUFFIXES


def add_profile_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Register `companion profile import` and `companion profile export`."""
    p = sub.add_parser("profile", help="a profile's fence and area from and to .plan, KML, GeoJSON")
    verbs = p.add_subparsers(dest="profile_command", required=True)
    i = verbs.add_parser("import", help="make a site fence (and area) from a drawn polygon")
    i.add_argument("file", type=Path, help=f"the drawn fence ({', '.join(SUFFIXES)})")
    i.add_argument("--into", type=Path, required=True, help="profile YAML to write")
    i.add_argument("--base", help="profile file or built-in name to start from (default: --into)")
    i.add_argument(
        "--margin",
        type=float,
        default=0.0,
        help="m between the fence's bounding rectangle and the search area (default 0)",
    )
    i.add_argument(
        "--keep-area",
        action="store_true",
        help="keep the profile's origin and area; replace only site.geofence",
    )
    i.add_argument(
        "--targets",
        choices=("ground", "frame", "fit"),
        default="ground",
        help="ground: targets keep their WGS84 position; frame: their metres from "
        "the new origin; fit: their place scaled to the new area",
    )
    i.add_argument("--alt", type=float, help="origin altitude AMSL, m (default: the profile's)")
    e = verbs.add_parser("export", help="write a profile's fence, area, starts and targets")
    e.add_argument("profile", help="profile file or built-in name")
    e.add_argument("--plan", type=Path, help="QGroundControl plan to write (the fence)")
    e.add_argument("--kml", type=Path, help="KML to write (fence, area, start points, targets)")
    e.add_argument("--geojson", type=Path, help="GeoJSON to write (the same as --kml)")
    e.add_argument("--seed", type=int, default=0, help="start points of `companion run --seed`")
    e.add_argument(
        "--firmware",
        choices=tuple(FIRMWARE_TYPES),
        default="ardupilot",
        help="the plan's firmware type (QGC offers its commands)",
    )
