"""`companion profile import` (a fence drawn in QGroundControl, Google Earth or a GIS into a
profile) and `companion profile export` (a profile's fence, area, start points and targets out
for them)."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from functools import partial
from pathlib import Path

from mdm_ground.site_files.fence_polygon import SiteFileError
from mdm_ground.site_files.geojson_file import write_geojson
from mdm_ground.site_files.kml_file import write_kml
from mdm_ground.site_files.plan_file import write_plan
from mdm_ground.site_files.profile_from_fence import FenceImport, profile_with_fence
from mdm_ground.site_files.read_fence import read_fence_file
from mdm_ground.site_files.site_layers import SiteLayers, site_layers
from mdm_profiles import load_profile, write_profile


def profile_command(args: argparse.Namespace) -> int:
    """`companion profile import|export`."""
    if args.profile_command == "import":
        return _import(args)
    return _export(args)


def _import(args: argparse.Namespace) -> int:
    base_name = args.base or args.into
    if args.base is None and not Path(args.into).is_file():
        raise SiteFileError(
            f"--into {args.into}: no such profile; give --base (a profile file "
            "or a built-in name such as field-duebendorf) to start from"
        )
    base = load_profile(base_name)
    fence = read_fence_file(args.file)
    how = FenceImport(args.margin, args.keep_area, args.targets, args.alt)
    profile = profile_with_fence(base, fence, str(args.file), how)
    try:
        write_profile(profile, args.into)
    except OSError as exc:
        raise SiteFileError(f"{args.into}: cannot be written: {exc.strerror or exc}") from exc
    o, a = profile.origin, profile.area
    print(f"fence: {len(fence.vertices)} vertices from {args.file}")
    print(
        f"origin: {o.lat:.7f}, {o.lon:.7f}, {o.alt:g} m AMSL; area: {a.north:g} m north x "
        f"{a.east:g} m east{' (kept)' if args.keep_area else ''}"
    )
    print(f"wrote {args.into}")
    return 0


def _export(args: argparse.Namespace) -> int:
    outputs = [(args.plan, "plan"), (args.kml, "kml"), (args.geojson, "geojson")]
    if all(path is None for path, _ in outputs):
        raise SiteFileError("companion profile export: give --plan, --kml and/or --geojson")
    layers = site_layers(load_profile(args.profile), args.seed)
    writers: dict[str, Callable[[SiteLayers, Path], None]] = {
        "plan": partial(write_plan, firmware=args.firmware),
        "kml": write_kml,
        "geojson": write_geojson,
    }
    for path, kind in outputs:
        if path is None:
            continue
        try:
            writers[kind](layers, path)
        except OSError as exc:
            raise SiteFileError(f"{path}: cannot be written: {exc.strerror or exc}") from exc
        print(f"wrote {path}")
    return 0
