"""Markers come from the fixtures a test uses: the names other engineers' new tests will use get
the right marker, and a test with none of them stays in the core."""

from __future__ import annotations

import pytest

from tests.markers import MARKERS, markers_for


@pytest.mark.parametrize(
    ("fixtures", "expected"),
    [
        (["arducopter", "tmp_path"], {"sitl"}),
        (["px4"], {"sitl"}),
        (["sitl_start"], {"sitl"}),
        (["sitl_team_of_three"], {"sitl"}),
        (["docker_images"], {"docker"}),
        (["mqtt_broker"], {"broker"}),
        (["mosquitto"], {"broker"}),
        (["chromium"], {"browser"}),
        (["browser_page"], {"browser"}),
        (["fleet_processes"], {"fleet"}),
        (["install_vehicle_venv"], {"install"}),
        (["fleet_processes", "mqtt_broker", "px4"], {"fleet", "broker", "sitl"}),
        (["tmp_path", "capsys", "monkeypatch", "images", "broker", "arducopter_log"], set()),
    ],
)
def test_a_test_gets_the_markers_of_its_fixtures_and_only_those(
    fixtures: list[str], expected: set[str]
) -> None:
    assert markers_for(fixtures) == expected


def test_every_marker_given_is_registered_with_a_description() -> None:
    every = [
        "arducopter",
        "px4",
        "sitl_x",
        "docker_x",
        "mqtt_broker",
        "mosquitto",
        "chromium",
        "browser_x",
        "fleet_x",
        "install_x",
    ]
    assert markers_for(every) == set(MARKERS)
    assert all(description.strip() for description in MARKERS.values())


def test_this_test_has_no_marker_of_a_service(request: pytest.FixtureRequest) -> None:
    assert not [m.name for m in request.node.iter_markers() if m.name in MARKERS]


def test_a_test_using_the_broker_is_marked_broker(
    request: pytest.FixtureRequest, mqtt_broker: int
) -> None:
    assert request.node.get_closest_marker("broker") is not None
    assert mqtt_broker == 1883
