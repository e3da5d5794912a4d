"""A site file's fence, whichever of the formats it is in (by its name's suffix)."""

from __future__ import annotations

from pathlib import Path

from mdm_ground.site_files.fence_polygon import FencePolygon, SiteFileError
from mdm_ground.site_files.formats import SUFFIXES
from mdm_ground.site_files.geojson_file import read_geojson
from mdm_ground.site_files.kml_file import read_kml
from mdm_ground.site_files.plan_file import read_plan

READERS = {".plan": read_plan, ".kml": read_kml, ".geojson": read_geojson, ".json": read_geojson}


def read_fence_file(path: Path) -> FencePolygon:
    """The fence drawn in ``path``: a QGroundControl .plan, a KML or a GeoJSON file."""
    suffix = path.suffix.lower()
    if suffix == ".kmz":
        raise SiteFileError(f"{path}: a KMZ (zip) file: unzip it and import its doc.kml")
    reader = READERS.get(suffix)
    if reader is None:
        raise SiteFileError(
            f"{path}: not a site file this reads ({', '.join(SUFFIXES)}): {suffix or 'no suffix'}"
        )
    if not path.is_file():
        raise SiteFileError(f"{path}: no such file")
    try:
        return reader(path)
    except OSError as exc:
        raise SiteFileError(f"{path}: cannot be read: {exc.strerror or exc}") from exc
