"""Fixtures shared by every test folder."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

from tests import sitl
from tests.mqtt_harness import clear_retained_of_this_run

if TYPE_CHECKING:
    from selenium.webdriver.chrome.webdriver import WebDriver


def _sitl_factory(kind: sitl.Kind, tmp_path: Path) -> Iterator[Callable[..., sitl.SitlInstance]]:
    if sitl.sitl_dir(kind) is None:
        pytest.skip(sitl.skip_reason(kind))
    started: list[sitl.SitlInstance] = []

    def start(**options: Any) -> sitl.SitlInstance:
        instance = sitl.start(kind, tmp_path / f"{kind}-{len(started)}", **options)
        started.append(instance)
        return instance

    yield start
    for instance in started:
        instance.stop()


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
def chromium(tmp_path: Path) -> Iterator[WebDriver]:
    """Headless Chromium (Debian's, through Selenium and /usr/bin/chromedriver) with a fresh
    profile; skips naming what is missing (fails under CI=true); quit at teardown."""
    from tests import browser

    why = browser.missing_parts()
    if why is not None:
        if browser.in_ci():
            pytest.fail(f"CI=true and {why}", pytrace=False)
        pytest.skip(why)
    driver = browser.start(tmp_path / "chromium-profile")
    try:
        yield driver
    finally:
        driver.quit()


@pytest.fixture(scope="session", autouse=True)
def _leave_no_retained_messages() -> Iterator[None]:
    """The fleets of MQTT tests publish a retained status per vehicle on the broker at
    127.0.0.1:1883 (the user's); the session clears what it left there."""
    yield
    clear_retained_of_this_run()
