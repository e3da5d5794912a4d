"""Fixtures shared by every test folder."""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from tests import sitl
from tests.markers import MARKERS, markers_for
from tests.mqtt_harness import clear_retained_of_this_run
from tests.services import missing

pytest_plugins = ["tests.service_fixtures"]


def pytest_configure(config: pytest.Config) -> None:
    for name, description in MARKERS.items():
        config.addinivalue_line("markers", f"{name}: {description}")


@pytest.hookimpl(tryfirst=True)  # before -m deselects by them
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Each test gets the markers of the fixtures it uses (tests/markers.py)."""
    for item in items:
        for marker in sorted(markers_for(getattr(item, "fixturenames", ()))):
            item.add_marker(marker)


def _sitl_starter(tmp_path: Path) -> Iterator[Callable[..., sitl.SitlInstance]]:
    """``start(kind, **options)``: one more instance of ``kind`` (skips, or fails under
    ``CI=true``, where there is no build of it); every instance is ended at teardown."""
    started: list[sitl.SitlInstance] = []

    def start(kind: sitl.Kind, **options: Any) -> sitl.SitlInstance:
        if sitl.sitl_dir(kind) is None:
            missing(sitl.skip_reason(kind))
        instance = sitl.start(kind, tmp_path / f"{kind}-{len(started)}", **options)
        started.append(instance)
        return instance

    yield start
    for instance in started:
        instance.stop()


def _sitl_factory(kind: sitl.Kind, tmp_path: Path) -> Iterator[Callable[..., sitl.SitlInstance]]:
    if sitl.sitl_dir(kind) is None:
        missing(sitl.skip_reason(kind))
    for start in _sitl_starter(tmp_path):
        yield functools.partial(start, kind)


@pytest.fixture
def arducopter(tmp_path: Path) -> Iterator[Callable[..., sitl.SitlInstance]]:
    """Start stock ArduCopter SITL instances (``arducopter(home=..., speedup=...)``); skips
    with the reason where no binary is found; every instance is ended at teardown."""
    yield from _sitl_factory("arducopter", tmp_path)


@pytest.fixture
def px4(tmp_path: Path) -> Iterator[Callable[..., sitl.SitlInstance]]:
    """Start stock PX4 SITL (SIH) instances (``px4(home=...)``); as ``arducopter``."""
    yield from _sitl_factory("px4", tmp_path)


@pytest.fixture
def sitl_start(tmp_path: Path) -> Iterator[Callable[..., sitl.SitlInstance]]:
    """For a test whose autopilot is a parameter: ``sitl_start(kind, home=..., speedup=...)``
    starts an instance of ``kind`` as ``arducopter`` / ``px4`` do (skipping where there is none)."""
    yield from _sitl_starter(tmp_path)


@pytest.fixture(scope="session", autouse=True)
def _leave_no_retained_messages() -> Iterator[None]:
    """The fleets of MQTT tests publish a retained status per vehicle on the broker at
    127.0.0.1:1883 (the user's); the session clears what it left there."""
    yield
    clear_retained_of_this_run()
