"""`companion fleet --web` in headless Chromium: the emulator's team live on the page, and an
abort clicked on the page flown by that vehicle alone."""

from __future__ import annotations

import os
import signal
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from companion.telemetry.mission_log import read_records
from tests.fleet_cli import start_fleet
from tests.ground.live_web.page import (
    cell,
    command,
    count,
    markers,
    open_page,
    page_url,
    screenshot,
)
from tests.mqtt_harness import retained_topics
from tests.profile_files import sensors, write_profile_with
from tests.waiting import wait_until

if TYPE_CHECKING:
    from selenium.webdriver.chrome.webdriver import WebDriver

VEHICLES = 3


def _profile(tmp_path: Path) -> Path:
    """Three vehicles, two real targets and a false one on a 3 km square; a 200 m confirmation
    sensor so that the team confirms within a minute or two of sim time."""
    return write_profile_with(
        tmp_path / "profile.yaml",
        "live-web-test",
        fleet={"vehicles": VEHICLES},
        targets=[
            {"north": 1500.0, "east": 1500.0},
            {"north": 700.0, "east": 700.0},
            {"north": 600.0, "east": 2400.0, "false_target": True},
        ],
        sensors=sensors(1000.0, 200.0),
        policy={"memory_radius": 300.0},
    )


def _emulator_modes(run: Path, vehicle: int) -> list[str]:
    return [
        r["mode"]
        for r in read_records(run / "emulator-events.jsonl")
        if r.get("event") == "mode" and r.get("vehicle") == vehicle
    ]


def _stale_rows(driver: WebDriver) -> list[str]:
    return list(
        driver.execute_script(
            "return [...document.querySelectorAll('#team tbody tr.stale')].map(r => r.dataset.vehicle)"
        )
    )


@pytest.mark.timeout(300)
def test_live_page_shows_the_team_moving_and_confirming_and_one_abort_flies_rtl(
    chromium: WebDriver, mqtt_broker: int, fleet_processes: Path
) -> None:
    tmp_path = fleet_processes
    prefix = f"mdm/test-{os.getpid()}-liveweb"
    run, output = tmp_path / "run", tmp_path / "fleet.out"
    fleet = start_fleet(
        "--profile", str(_profile(tmp_path)), "--out", str(run), "--speedup", "10",
        "--duration", "900", "--seed", "3", "--land-wait", "100", "--web", "127.0.0.1:0",
        "--mqtt", f"127.0.0.1:{mqtt_broker}", "--mqtt-prefix", prefix, output=output,
    )  # fmt: skip
    try:
        open_page(chromium, page_url(output, fleet))
        first = wait_until(
            lambda: markers(chromium),
            60,
            f"{VEHICLES} vehicle markers",
            until=lambda m: len(m) == VEHICLES,
        )
        assert count(chromium, "#team tbody tr") == VEHICLES
        assert count(chromium, "#area #fence") == 1
        assert count(chromium, "#targets text") == 3
        wait_until(
            lambda: markers(chromium),
            60,
            "every marker to move",
            until=lambda m: all(m[i] != first[i] for i in range(VEHICLES)),
        )
        wait_until(
            lambda: [cell(chromium, i, 3) for i in range(VEHICLES)],
            60,
            "every vehicle searching",
            until=lambda p: p == ["search"] * VEHICLES,
        )
        screenshot(chromium, tmp_path, "live-fleet-searching")

        command(chromium, 0, "abort")
        wait_until(
            lambda: chromium.find_element("id", "commands").text,
            30,
            "vehicle 0's acceptance of the abort on the page",
            until=lambda text: "abort -> uav0" in text and "uav0: accepted" in text,
        )
        wait_until(
            lambda: _emulator_modes(run, 0),
            30,
            "vehicle 0 in RTL (emulator's log)",
            until=lambda modes: modes and modes[-1] == "RTL",
        )
        wait_until(
            lambda: cell(chromium, 0, 1),
            30,
            "RTL shown for vehicle 0",
            until=lambda mode: mode == "RTL",
        )
        screenshot(chromium, tmp_path, "live-fleet-after-abort")

        wait_until(
            lambda: count(chromium, "#marks .confirmation"), 120, "a confirmation on the page"
        )
        # the others searched on: neither went home, both are still in the search
        for i in range(1, VEHICLES):
            assert "RTL" not in _emulator_modes(run, i), _emulator_modes(run, i)
            assert cell(chromium, i, 1) != "RTL"
        assert cell(chromium, 0, 3).startswith(("return", "done")), cell(chromium, 0, 3)
        # its companion ended with the mission: silent now, so shown stale; the others are not
        wait_until(
            lambda: _stale_rows(chromium),
            30,
            "uav0 shown stale, alone",
            until=lambda rows: rows == ["0"],
        )
        screenshot(chromium, tmp_path, "live-fleet-confirmation")
    finally:
        if fleet.poll() is None:
            os.killpg(fleet.pid, signal.SIGINT)
            try:
                fleet.wait(60)
            except Exception:
                os.killpg(fleet.pid, signal.SIGKILL)
                raise
        retained_topics(mqtt_broker, f"{prefix}/#", remove=True)
