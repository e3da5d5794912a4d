"""The file kinds `companion profile` reads and writes, named once for the readers and the
command line (which must not import the readers' libraries to offer them)."""

from __future__ import annotations

SUFFIXES = (".plan", ".kml", ".geojson", ".json")
"""Site files read, by name: a QGroundControl plan, KML, GeoJSON (.json too)."""
FIRMWARE_TYPES = {"ardupilot": 3, "px4": 12}
"""MAV_AUTOPILOT of a written plan's mission: QGroundControl offers that firmware's commands."""
