"""The detector's JSON on <prefix>/uav<i>/detections: what is accepted and what each refusal says."""

from __future__ import annotations

import json

import pytest

from companion.link.local_frame import LocalFrame
from companion.sensors.detection_payload import DetectionError, parse_detection

NAMES = ("detection", "confirmation")
FRAME = LocalFrame(47.3960, 8.6380, 440.0)


def parse(data: object) -> object:
    return parse_detection(json.dumps(data).encode(), NAMES, FRAME)


def test_lat_lon_is_converted_to_the_profiles_frame() -> None:
    lat, lon, _ = FRAME.to_geodetic(300.0, 500.0, 0.0)
    d = parse_detection(
        json.dumps(
            {"time": 1.5, "sensor": "confirmation", "lat": lat, "lon": lon, "confidence": 0.8}
        ).encode(),
        NAMES,
        FRAME,
    )
    assert d.sensor == 1
    assert d.position == pytest.approx((300.0, 500.0), abs=1e-3)
    assert d.confidence == 0.8


def test_a_frame_without_a_position_says_nothing_was_seen() -> None:
    d = parse_detection(b'{"time": 3, "sensor": 0}', NAMES, FRAME)
    assert d.position is None
    assert d.sensor == 0


@pytest.mark.parametrize(
    ("payload", "message"),
    [
        (b"{not json", "not JSON"),
        (b"[1, 2]", "expected a JSON object, got list"),
        (b'{"sensor": 0}', "time: missing"),
        (
            b'{"time": 1, "sensor": "lidar"}',
            "sensor 'lidar': expected one of detection, confirmation",
        ),
        (b'{"time": 1, "sensor": 2}', "sensor 2: expected one of"),
        (b'{"time": 1, "sensor": 0, "north": 5}', "north and east go together"),
        (b'{"time": 1, "sensor": 0, "lat": 47.4}', "lat and lon go together"),
        (b'{"time": 1, "sensor": 0, "lat": 91, "lon": 8}', "is not a WGS84 position"),
        (b'{"time": 1, "sensor": 0, "lat": 47, "lon": 8, "north": 1, "east": 1}', "not both"),
        (b'{"time": 1, "sensor": 0, "north": "x", "east": 1}', "north: expected a finite number"),
        (b'{"time": NaN, "sensor": 0}', "time: expected a finite number"),
        (b'{"time": 1, "sensor": 0, "confidence": 1.5}', "confidence 1.5: expected 0-1"),
        (b'{"time": 1, "sensor": 0, "north": 1e38, "east": 1}', "more than 200 km from the"),
        (b'{"time": 1, "sensor": 0, "x": 1}', "unknown field(s) x"),
    ],
)
def test_bad_payloads_are_refused_with_the_reason(payload: bytes, message: str) -> None:
    with pytest.raises(DetectionError, match=message.replace("(", r"\(").replace(")", r"\)")):
        parse_detection(payload, NAMES, FRAME)
