"""What a vehicle's mission log says about where it went and what it found (profile frame)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from companion.telemetry import events
from companion.telemetry.mission_log import read_log, read_records


@dataclass(frozen=True)
class Sample:
    """One logged point: mission time (vehicle s) and metres north/east of the profile origin."""

    t: float
    north: float
    east: float


@dataclass
class VehicleTrack:
    """One vehicle's run, read back from ``mission-<vehicle>.jsonl``."""

    vehicle: int
    path: list[Sample] = field(default_factory=list)
    """The ``tick`` positions (every 10 vehicle s), in log order."""
    detections: list[tuple[Sample, int]] = field(default_factory=list)
    """Where the vehicle was when a detection raised its level, and the new level."""
    confirmations: list[Sample] = field(default_factory=list)
    """Where each confirmed target was reported."""
    lanes: list[tuple[float, float]] = field(default_factory=list)
    """A lawnmower vehicle's planned lanes (the ``lawnmower_lanes`` record: lane k from point
    2k to 2k + 1, north/east, inside the guidance fence); empty for other methods."""
    end_reason: str | None = None
    origin: tuple[float, float] | None = None
    """(lat, lon) where the vehicle's own frame starts, for a vehicle flown in that frame (a
    profile without ``site``, the mission log's ``frame`` record of source ``own``); None: its
    positions are in the profile's frame."""


def read_track(path: Path, vehicle: int) -> VehicleTrack:
    """The track in one mission log; ``tick`` records without a usable position are skipped."""
    logged = read_log(path)
    end = logged.end()
    track = VehicleTrack(vehicle, end_reason=None if end is None else end.reason)
    for e in logged.events:
        if isinstance(e.event, events.Detection):
            where = Sample(e.t, e.event.north, e.event.east)
            track.detections.append((where, e.event.level))
        elif isinstance(e.event, events.Confirmation):
            track.confirmations.append(Sample(e.t, e.event.north, e.event.east))
    for record in read_records(path):
        if record.get("event") == "frame" and record.get("source") == "own":
            try:
                track.origin = (float(record["lat"]), float(record["lon"]))
            except (KeyError, TypeError, ValueError):
                continue
        elif record.get("event") == "lawnmower_lanes":
            try:
                track.lanes = [(float(n), float(e)) for n, e in record["lanes"]]
            except (KeyError, TypeError, ValueError):
                continue
        elif record.get("event") == "tick":
            try:
                track.path.append(
                    Sample(float(record["t"]), float(record["north"]), float(record["east"]))
                )
            except (KeyError, TypeError, ValueError):
                continue  # a damaged tick costs one point of the path, not the map
    return track


def read_tracks(log_dir: Path, vehicles: list[int]) -> list[VehicleTrack]:
    """The tracks of ``vehicles`` from ``log_dir/mission-<i>.jsonl`` (missing logs: empty)."""
    return [read_track(log_dir / f"mission-{i}.jsonl", i) for i in vehicles]
