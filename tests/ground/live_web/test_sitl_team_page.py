"""`companion fleet --sitl mixed --web` without any broker, in headless Chromium: an ArduCopter
and a PX4 SITL instance on the page, each in its autopilot's own guided mode name (GUIDED,
OFFBOARD: companion/autopilots' tables), an abort to all clicked on the page flown by both
(their autopilots' second links say RTL), RTL on the page and both answers in its event log."""

from __future__ import annotations

import json
import os
import signal
import time
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from companion.autopilots.ardupilot import ArduCopter
from companion.autopilots.base import Autopilot, FlightMode
from companion.autopilots.px4 import PX4
from tests.companion.sitl_observer import Observer
from tests.companion.sitl_team import fence_polygon, figures, observe, team_of, team_profile
from tests.fleet_cli import start_fleet
from tests.ground.live_web.page import cell, command, open_page, page_url, screenshot
from tests.waiting import wait_until

if TYPE_CHECKING:
    from selenium.webdriver.chrome.webdriver import WebDriver

SPEEDUP = 2.0
"""SITL speed-up of tests/ground/test_fleet_sitl_team.py (four instances kept 10 Hz there)."""
SEED = 3
AUTOPILOTS: dict[str, Autopilot] = {"arducopter": ArduCopter(), "px4": PX4()}


def _tail(path: Path) -> str:
    return path.read_text(errors="replace")[-3000:] if path.exists() else "(no output)"


def _log(driver: WebDriver, kind: str) -> list[str]:
    return list(driver.execute_script(
        f"return [...document.querySelectorAll('#log li[data-kind={kind}]')]"
        ".map(li => li.textContent)"
    ))  # fmt: skip


@pytest.mark.timeout(1500)
def test_a_mixed_sitl_team_on_the_page_shows_each_autopilots_modes_and_flies_its_abort(
    sitl_both: None, chromium: WebDriver, tmp_path: Path
) -> None:
    profile = team_profile(tmp_path, vehicles=2, seed=SEED, duration=600.0)
    out, output = tmp_path / "run", tmp_path / "fleet.out"
    fleet = start_fleet("--profile", str(profile), "--sitl", "mixed", "--sitl-speedup",
                        str(SPEEDUP), "--seed", str(SEED), "--out", str(out), "--land-wait", "600", "--flight-log-wait", "0",
                        "--quiet", "--web", "127.0.0.1:0", output=output)  # fmt: skip
    observers: dict[int, Observer] = {}
    try:
        url = page_url(output, fleet, timeout=300.0)
        team = team_of(out)
        kinds = {e.index: str(e.autopilot) for e in team}
        assert sorted(kinds.values()) == ["arducopter", "px4"], kinds
        pilots = {i: AUTOPILOTS[k] for i, k in kinds.items()}
        named = {
            mode: {i: p.mode_name(p.custom_mode(mode)) for i, p in pilots.items()}
            for mode in (FlightMode.GUIDED, FlightMode.RTL)
        }
        assert sorted(named[FlightMode.GUIDED].values()) == ["GUIDED", "OFFBOARD"]
        observers = observe(team)
        open_page(chromium, url)
        wait_until(lambda: {i: (cell(chromium, i, 1), cell(chromium, i, 3)) for i in kinds},
                   600.0, "both vehicles searching in their own guided mode on the page",
                   until=lambda shown: shown == {i: (named[FlightMode.GUIDED][i], "search")
                                                 for i in kinds},
                   context=lambda: _tail(output))  # fmt: skip
        screenshot(chromium, tmp_path, "sitl-team-searching")

        command(chromium, "all", "abort")
        rtl = {i: p.custom_mode(FlightMode.RTL) for i, p in pilots.items()}
        asked = time.monotonic()
        wait_until(lambda: {i: o.snapshot().mode for i, o in observers.items()}, 60.0,
                   "both autopilots in RTL (their second links)",
                   until=lambda modes: modes == rtl)  # fmt: skip
        print(f"\nwall s from the page's abort to both autopilots in RTL: "
              f"{time.monotonic() - asked:.1f}")  # fmt: skip
        wait_until(lambda: {i: cell(chromium, i, 1) for i in kinds}, 30.0, "RTL on the page",
                   until=lambda shown: shown == named[FlightMode.RTL])  # fmt: skip
        answers = wait_until(lambda: _log(chromium, "command"), 30.0, "both answers logged",
                             until=lambda lines: len(lines) == 2)  # fmt: skip
        assert sorted(line.split()[1] for line in answers) == ["uav0", "uav1"], answers
        assert all("command abort accepted" in line for line in answers), answers
        screenshot(chromium, tmp_path, "sitl-team-after-abort")
        code = fleet.wait(timeout=900)
        traces = {i: o.snapshot() for i, o in observers.items()}
    finally:
        if fleet.poll() is None:
            os.killpg(fleet.pid, signal.SIGKILL)
        for o in observers.values():
            o.close()
    assert code == 0, _tail(output)
    for i, t in traces.items():
        f = figures(t, kinds[i], fence_polygon(profile))
        assert f.end == "landed, disarmed", f.line(i, kinds[i])
    result = json.loads((out / "results.json").read_text())
    assert {e["how"] for e in result["ends"]} == {"operator abort"}, result["ends"]
    assert json.loads((out / "run.json").read_text())["mqtt"]["broker"] == "embedded"
