"""Fixtures for the services a test needs from outside the package: the MQTT broker (the one on
127.0.0.1:1883, or one of the test's own), headless Chromium, and the processes of a fleet. Each
skips naming what is missing (fails under ``CI=true``: tests/services.py); their names give the
test its marker (tests/markers.py)."""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from selenium import webdriver
from selenium.webdriver.chrome.options import Options
from selenium.webdriver.chrome.service import Service

from tests import sitl
from tests.fleet_cli import processes_naming
from tests.mqtt_harness import Broker
from tests.services import (
    MQTT_PORT,
    broker_missing,
    chromium_missing,
    missing,
    mosquitto_missing,
)
from tests.waiting import wait_until


@pytest.fixture(scope="session")
def mqtt_broker() -> int:
    """The Mosquitto broker on 127.0.0.1:1883 (the user's, or the one ``.ci/run`` starts), with
    the mosquitto_sub / mosquitto_pub clients tests watch it with; its port."""
    reason = broker_missing()
    if reason is not None:
        missing(reason)
    return MQTT_PORT


@pytest.fixture
def mosquitto(tmp_path: Path) -> Iterator[Callable[..., Broker]]:
    """Brokers of the test's own: ``mosquitto(name, security=...)`` makes a ``Broker`` (not yet
    started) in ``tmp_path/name`` on a free port; every one is stopped at teardown."""
    reason = mosquitto_missing()
    if reason is not None:
        missing(reason)
    made: list[Broker] = []

    def make(name: str = "broker", **options: Any) -> Broker:
        broker = Broker(tmp_path / name, **options)
        made.append(broker)
        return broker

    yield make
    for broker in made:
        broker.stop()


@pytest.fixture
def sitl_both() -> None:
    """Both SITL builds (ArduCopter and PX4) are needed (a mixed team); skips with the
    variable to set."""
    for kind in ("arducopter", "px4"):
        if sitl.sitl_dir(kind) is None:
            missing(sitl.skip_reason(kind))


@pytest.fixture
def chromium() -> Iterator[webdriver.Chrome]:
    """A headless Chromium (``chromium`` and ``chromedriver`` from PATH, as Debian's chromium and
    chromium-driver packages put them in /usr/bin) driven through Selenium, with a fresh profile
    in a folder of its own (outside the test's, which ``fleet_processes`` watches) and none of
    its background connections (this machine's network is closed: they would fail, many at a
    time); nothing is downloaded. Quit at teardown."""
    reason = chromium_missing()
    if reason is not None:
        missing(reason)
    options = Options()
    options.binary_location = str(shutil.which("chromium"))
    for arg in (
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-dev-shm-usage",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--window-size=1600,1000",
    ):
        options.add_argument(arg)
    profile = tempfile.mkdtemp(prefix="mdm-chromium-")
    options.add_argument(f"--user-data-dir={profile}")
    session = webdriver.Chrome(
        options=options, service=Service(executable_path=str(shutil.which("chromedriver")))
    )
    try:
        yield session
    finally:
        session.quit()
        shutil.rmtree(profile, ignore_errors=True)


@pytest.fixture
def fleet_processes(tmp_path: Path) -> Iterator[Path]:
    """For a test that runs a fleet (``companion fleet``, or an emulator and companions of its
    own) with its files in ``tmp_path``: yields ``tmp_path``. At teardown no process naming
    ``tmp_path`` may be left: any still alive after 5 s is killed and the test errors naming
    it, so that a failed test does not leave a fleet flying on the shared cores."""
    yield tmp_path
    try:
        wait_until(lambda: processes_naming(str(tmp_path)), 5.0, "the test's processes gone",
                   until=lambda left: not left)  # fmt: skip
    except AssertionError:
        left = processes_naming(str(tmp_path))
        for pid in left:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        if left:
            pytest.fail(f"processes left running by the test (killed): {left}", pytrace=False)
