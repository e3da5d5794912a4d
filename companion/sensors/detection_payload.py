"""The JSON an onboard detector publishes on ``<prefix>/uav<i>/detections`` (docs/mqtt.md),
validated: every problem is a :class:`DetectionError` naming the field and what is allowed."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

from companion.errors import CompanionError
from companion.link.local_frame import LocalFrame

_FIELDS = frozenset({"time", "sensor", "lat", "lon", "north", "east", "confidence"})
MAX_DISTANCE = 200_000.0
"""Metres from the profile's origin a detection may be (the telemetry check's bound)."""


class DetectionError(CompanionError, ValueError):
    """A detection payload that cannot be used; the message says what is wrong."""


@dataclass(frozen=True)
class Detection:
    """One frame of the detector: what ``sensor`` saw (a position) or that it saw nothing."""

    time: float
    """UNIX time (s) the frame was taken, by the detector's clock."""
    sensor: int
    """Index into the profile's ``sensors``."""
    position: tuple[float, float] | None
    """(north, east) metres in the profile's frame; None: nothing seen (the detector is alive)."""
    confidence: float | None


def _number(data: dict[str, object], key: str) -> float:
    value = data[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise DetectionError(f"{key}: expected a finite number, got {value!r}")
    return float(value)


def _sensor(value: object, names: tuple[str, ...]) -> int:
    if isinstance(value, str) and value in names:
        return names.index(value)
    if isinstance(value, int) and not isinstance(value, bool) and 0 <= value < len(names):
        return value
    raise DetectionError(
        f"sensor {value!r}: expected one of {', '.join(names)} or an index 0-{len(names) - 1}"
    )


def parse_detection(payload: bytes, names: tuple[str, ...], frame: LocalFrame) -> Detection:
    """``payload`` -> Detection; ``names``: the profile's sensor names, ``frame``: its origin."""
    try:
        data = json.loads(payload)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DetectionError(f"not JSON: {exc}") from None
    if not isinstance(data, dict):
        raise DetectionError(f"expected a JSON object, got {type(data).__name__}")
    unknown = sorted(set(data) - _FIELDS)
    if unknown:
        raise DetectionError(
            f"unknown field(s) {', '.join(unknown)}; allowed: {', '.join(sorted(_FIELDS))}"
        )
    for key in ("time", "sensor"):
        if key not in data:
            raise DetectionError(f"{key}: missing")
    stamp = _number(data, "time")
    sensor = _sensor(data["sensor"], names)
    geo, local = {"lat", "lon"} & set(data), {"north", "east"} & set(data)
    if geo and local:
        raise DetectionError("give lat/lon or north/east, not both")
    position: tuple[float, float] | None = None
    if geo:
        if geo != {"lat", "lon"}:
            raise DetectionError("lat and lon go together")
        lat, lon = _number(data, "lat"), _number(data, "lon")
        if not (-90 <= lat <= 90 and -180 <= lon <= 180):
            raise DetectionError(f"lat/lon ({lat}, {lon}) is not a WGS84 position")
        north, east, _ = frame.to_local(lat, lon, frame.alt)
        position = (north, east)
    elif local:
        if local != {"north", "east"}:
            raise DetectionError("north and east go together")
        position = (_number(data, "north"), _number(data, "east"))
    if position is not None and max(abs(position[0]), abs(position[1])) > MAX_DISTANCE:
        raise DetectionError(
            f"position ({position[0]:g}, {position[1]:g}) m: more than "
            f"{MAX_DISTANCE / 1000:g} km from the profile's origin"
        )
    confidence = None
    if "confidence" in data:
        confidence = _number(data, "confidence")
        if not 0 <= confidence <= 1:
            raise DetectionError(f"confidence {confidence}: expected 0-1")
    return Detection(stamp, sensor, position, confidence)
