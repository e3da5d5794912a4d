"""The map of a live run: flown paths, detections, confirmations, targets and the fence, as
GeoJSON (RFC 7946) and a PNG with a scale bar, built from the mission logs."""

from mdm_ground.run_map.tracks import VehicleTrack, read_tracks
from mdm_ground.run_map.writer import write_run_map

__all__ = ["VehicleTrack", "read_tracks", "write_run_map"]
