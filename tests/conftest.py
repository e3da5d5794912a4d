"""Fixtures shared by every test folder."""

from __future__ import annotations

import functools
import os
from collections import Counter
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from mdm_ground.fleet.sitl_team import INSTANCE_BASE_ENV
from tests import kernel_warmup, parallel, sitl
from tests.markers import MARKERS, markers_for
from tests.mqtt_harness import clear_retained_of_this_run
from tests.services import missing

pytest_plugins = ["tests.service_fixtures"]


def pytest_configure(config: pytest.Config) -> None:
    for name, description in MARKERS.items():
        config.addinivalue_line("markers", f"{name}: {description}")


def pytest_sessionstart(session: pytest.Session) -> None:
    """With pytest-xdist's workers (``-n N``): the compiled kernels cached once, before the
    workers start, instead of compiled by each of them at once (tests/kernel_warmup.py)."""
    config = session.config
    if config.getoption("numprocesses", None) and not hasattr(config, "workerinput"):
        kernel_warmup.warm()


@pytest.hookimpl(wrapper=True)  # before every other plugin: -m deselects by them, xdist groups
def pytest_collection_modifyitems(
    config: pytest.Config, items: list[pytest.Item]
) -> Iterator[None]:
    """Each test gets the markers of the fixtures it uses (tests/markers.py) and its xdist
    group (tests/parallel.py)."""
    found = {item.nodeid: markers_for(getattr(item, "fixturenames", ())) for item in items}
    for item in items:
        for marker in sorted(found[item.nodeid]):
            item.add_marker(marker)
    sitl_modules = Counter(_module(i) for i in items if "sitl" in found[i.nodeid])
    lanes = parallel.sitl_lanes(dict(sitl_modules))
    for item in items:
        group = parallel.group_of(found[item.nodeid], _module(item), lanes)
        if group is not None:
            item.add_marker(pytest.mark.xdist_group(group))
    yield
    if config.getoption("loadgroup", False):  # a pytest-xdist worker of `--dist loadgroup`
        ungrouped = [
            i.nodeid for i in items if i.get_closest_marker("xdist_group") and "@" not in i.nodeid
        ]
        if ungrouped:  # pytest >= 9.2 keeps node ids where xdist 3.8 cannot add the group
            raise pytest.UsageError(
                f"pytest-xdist did not take the SITL and Docker groups (pytest {pytest.__version__}; "
                f"{ungrouped[0]} has none): install the versions pyproject.toml's dev extra pins"
            )


def _module(item: pytest.Item) -> str:
    return item.nodeid.split("::", 1)[0]


@pytest.fixture(autouse=True)
def _sitl_instance_base(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> None:
    """A SITL test takes instance indices from its lane's base on (tests/parallel.py), unless
    MDM_SITL_INSTANCE_BASE was set for the whole run."""
    marker = request.node.get_closest_marker("xdist_group")
    base = parallel.instance_base(marker.args[0] if marker else None)
    if base is not None and INSTANCE_BASE_ENV not in os.environ:
        monkeypatch.setenv(INSTANCE_BASE_ENV, str(base))


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
