"""The field profile: geo-referenced fence converted once to local metres; CLI input errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from companion.cli import main
from companion.fence_from_profile import fence_for
from companion.link.local_frame import LocalFrame
from mdm_profiles import load_profile


def test_field_fence_lies_inside_the_search_box() -> None:
    profile = load_profile("field-duebendorf")
    fence = fence_for(profile)
    assert np.all(fence.vertices >= 0)
    assert np.all(fence.vertices <= [profile.area.north, profile.area.east])
    assert np.allclose(fence.vertices[0], [40.0, 40.0], atol=0.5)


def test_local_frame_round_trip_is_centimetre_exact() -> None:
    frame = LocalFrame(47.396, 8.638, 440.0)
    lat, lon, alt = frame.to_geodetic(1160.0, 1940.0, -45.0)
    n, e, d = frame.to_local(lat, lon, alt)
    assert np.allclose([n, e, d], [1160.0, 1940.0, -45.0], atol=0.01)


def test_paper_profiles_fall_back_to_the_area_rectangle() -> None:
    fence = fence_for(load_profile("paper-fixed"))
    assert fence.contains(np.array([20000.0, 0.0]))
    assert not fence.contains(np.array([20001.0, 5.0]))


def test_bad_profile_is_a_clear_error_not_a_crash(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\narea: {north: -1, east: 5}\n")
    assert main(["run", "--profile", str(bad), "--vehicle", "0"]) == 2
    err = capsys.readouterr().err
    assert "bad.yaml" in err
    assert "area.north" in err


def test_vehicle_index_outside_the_fleet_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "--profile", "paper-fixed", "--vehicle", "12"]) == 2
    assert "12 vehicles" in capsys.readouterr().err
