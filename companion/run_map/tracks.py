"""What a vehicle's mission log says about where it went and what it found (profile frame)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from companion.telemetry.mission_log import read_records


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
    end_reason: str | None = None


def _sample(record: dict[str, Any]) -> Sample | None:
    try:
        return Sample(float(record["t"]), float(record["north"]), float(record["east"]))
    except (KeyError, TypeError, ValueError):
        return None


def read_track(path: Path, vehicle: int) -> VehicleTrack:
    """The track in one mission log; records without a usable position are skipped."""
    track = VehicleTrack(vehicle)
    for record in read_records(path):
        event = record.get("event")
        if event == "end":
            track.end_reason = str(record.get("reason"))
        if event not in ("tick", "detection", "confirmation"):
            continue
        sample = _sample(record)
        if sample is None:
            continue
        if event == "tick":
            track.path.append(sample)
        elif event == "detection":
            track.detections.append((sample, int(record.get("level", -1))))
        else:
            track.confirmations.append(sample)
    return track


def read_tracks(log_dir: Path, vehicles: list[int]) -> list[VehicleTrack]:
    """The tracks of ``vehicles`` from ``log_dir/mission-<i>.jsonl`` (missing logs: empty)."""
    return [read_track(log_dir / f"mission-{i}.jsonl", i) for i in vehicles]
