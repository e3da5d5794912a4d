"""`companion fleet --web` without any broker (the page runs the embedded one) in headless
Chromium: the emulator's team live on the page, the map zoomed and panned, an abort clicked on
the page flown by that vehicle alone, and the event log showing the command's answer and a
confirmation."""

from __future__ import annotations

import json
import math
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


def _view_box(driver: WebDriver) -> list[float]:
    box = driver.execute_script("return document.getElementById('map').getAttribute('viewBox')")
    return [float(v) for v in str(box).split()]


def _scale(driver: WebDriver) -> tuple[float, float]:
    """The scale bar: the metres its label says, and the metres its length covers on the map."""
    text, bar_px, per_px = driver.execute_script(
        "const m = document.getElementById('map'); const v = m.getAttribute('viewBox').split(' ');"
        "return [document.getElementById('scale-text').textContent,"
        " parseFloat(document.getElementById('scale-bar').style.width),"
        " Math.max(Number(v[2]) / m.clientWidth, Number(v[3]) / m.clientHeight)];"
    )
    number, unit = str(text).split()
    return float(number) * (1000.0 if unit == "km" else 1.0), float(bar_px) * float(per_px)


def _log(driver: WebDriver, kind: str) -> list[str]:
    """The event log's lines of ``kind`` shown now (newest first)."""
    return list(driver.execute_script(
        f"return [...document.querySelectorAll('#log li[data-kind=\"{kind}\"]')]"
        ".filter(li => !li.hidden).map(li => li.textContent)"
    ))  # fmt: skip


@pytest.mark.timeout(300)
def test_live_page_without_a_broker_shows_the_team_and_an_abort_is_flown_and_logged(
    chromium: WebDriver, fleet_processes: Path
) -> None:
    tmp_path = fleet_processes
    run, output = tmp_path / "run", tmp_path / "fleet.out"
    fleet = start_fleet(
        "--profile", str(_profile(tmp_path)), "--out", str(run), "--speedup", "10",
        "--duration", "900", "--seed", "3", "--land-wait", "100", "--web", "127.0.0.1:0",
        output=output,
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
        assert "embedded amqtt" in chromium.find_element("id", "broker").text
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

        # zoom: the buttons scale the view box about its centre, fit brings the area back;
        # the scale bar says what its length is on the map at each zoom
        fitted, fitted_scale = _view_box(chromium), _scale(chromium)
        chromium.find_element("id", "zoom-in").click()
        chromium.find_element("id", "zoom-in").click()
        zoomed = _view_box(chromium)
        assert zoomed[2] == pytest.approx(fitted[2] / 2.25, rel=1e-3)
        assert zoomed[0] + zoomed[2] / 2 == pytest.approx(fitted[0] + fitted[2] / 2, abs=1.0)
        zoomed_scale = _scale(chromium)
        assert zoomed_scale[0] < fitted_scale[0]
        for said, shown in (fitted_scale, zoomed_scale):
            assert shown == pytest.approx(said, rel=0.02)
        chromium.find_element("css selector", '#team tbody tr[data-vehicle="1"] td').click()
        before = markers(chromium)[1]
        chromium.find_element("id", "centre").click()
        centred = _view_box(chromium)
        after = markers(chromium)[1]
        # on the vehicle as it was at the click: somewhere on its way from before to after (it
        # flies on at 20 m/s x 10, and a loaded host takes a while between the two reads)
        centre = (-(centred[1] + centred[3] / 2), centred[0] + centred[2] / 2)  # north, east
        assert _to_segment(centre, before, after) < 60.0, (centre, before, after)
        assert count(chromium, '#vehicles g.selected[data-vehicle="1"]') == 1
        assert count(chromium, '#team tr.selected[data-vehicle="1"]') == 1
        screenshot(chromium, tmp_path, "live-fleet-zoomed-uav1")
        chromium.find_element("id", "fit").click()
        assert _view_box(chromium) == pytest.approx(fitted)

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
        (sent,) = _log(chromium, "sent")
        assert "uav0 operator sent abort to uav0" in sent
        (answer,) = _log(chromium, "command")
        assert "uav0 command abort accepted" in answer
        screenshot(chromium, tmp_path, "live-fleet-after-abort")

        wait_until(
            lambda: count(chromium, "#marks .confirmation"), 120, "a confirmation on the page"
        )
        confirmed = wait_until(
            lambda: _log(chromium, "confirmation"), 10, "the confirmation in the event log"
        )
        assert all(" confirmation at N " in line for line in confirmed), confirmed
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
        # one vehicle's log: uav2's lines and those to all only
        from selenium.webdriver.support.ui import Select

        Select(chromium.find_element("id", "log-filter")).select_by_value("2")
        assert _log(chromium, "sent") == []
        assert all("uav2" in line for line in _log(chromium, "phase"))
        screenshot(chromium, tmp_path, "live-fleet-confirmation-log-uav2")
    finally:
        if fleet.poll() is None:
            os.killpg(fleet.pid, signal.SIGINT)
            try:
                fleet.wait(60)
            except Exception:
                os.killpg(fleet.pid, signal.SIGKILL)
                raise
    broker = json.loads((run / "run.json").read_text())["mqtt"]
    assert broker["broker"] == "embedded"
    assert broker["server"].startswith("amqtt ")
    assert not (run / "broker-accounts").exists(), "the run's broker passwords left on disk"


def _to_segment(
    point: tuple[float, float], a: tuple[float, float], b: tuple[float, float]
) -> float:
    """Metres from ``point`` to the segment from ``a`` to ``b`` (north, east)."""
    dn, de = b[0] - a[0], b[1] - a[1]
    length2 = dn * dn + de * de
    s = 0.0 if length2 == 0 else ((point[0] - a[0]) * dn + (point[1] - a[1]) * de) / length2
    s = min(max(s, 0.0), 1.0)
    return math.hypot(point[0] - a[0] - s * dn, point[1] - a[1] - s * de)
