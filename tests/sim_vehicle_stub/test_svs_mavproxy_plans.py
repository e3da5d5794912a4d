"""MAVProxy (commands piped to its stdin) loads a mission, a fence and rally points into an
emulated vehicle of each persona, lists the mission back and flies it in AUTO: `wp load`,
`fence load`, `rally load`, `wp list`, then `mode guided`/`arm throttle`/`takeoff`/`mode auto`
(ArduPilot) or `long DO_SET_MODE 1 4 4`/`arm throttle` (PX4: MAVProxy's own `mode MISSION`
fails in MAVProxy on PX4, whatever the vehicle, so AUTO.MISSION is set by its command)."""

from __future__ import annotations

import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.emulator_harness import free_udp_base, make_config, running_emulator

STEP = 0.0003
"""Degrees between the waypoints (about 33 m north, 23 m east)."""


def _files(folder: Path, lat: float, lon: float, alt: float) -> tuple[Path, Path, Path]:
    rows = [
        (1, 0, 16, lat, lon, alt),
        (0, 3, 22, lat, lon, 10.0),
        (0, 3, 16, lat + STEP, lon, 10.0),
        (0, 3, 16, lat + STEP, lon + STEP, 10.0),
        (0, 2, 20, 0.0, 0.0, 0.0),
    ]
    wp = folder / "mission.txt"
    wp.write_text(
        "QGC WPL 110\n"
        + "".join(
            f"{k}\t{cur}\t{frame}\t{cmd}\t0\t0\t0\t0\t{a:.7f}\t{b:.7f}\t{z:.2f}\t1\n"
            for k, (cur, frame, cmd, a, b, z) in enumerate(rows)
        )
    )
    corners = [(-3, -3), (-3, 3), (3, 3), (3, -3)]
    fence = folder / "fence.txt"
    fence.write_text(
        "QGC WPL 110\n"
        + "".join(
            f"{k}\t0\t0\t5001\t4\t0\t0\t0\t{lat + a * STEP:.7f}\t{lon + b * STEP:.7f}\t0\t1\n"
            for k, (a, b) in enumerate(corners)
        )
    )
    rally = folder / "rally.txt"
    rally.write_text(
        f"QGC WPL 110\n0\t0\t3\t5100\t0\t0\t0\t0\t{lat + STEP:.7f}\t{lon:.7f}\t20\t1\n"
    )
    return wp, fence, rally


def _wait(until: Callable[[], bool], seconds: float) -> bool:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if until():
            return True
        time.sleep(0.1)
    return until()


@pytest.mark.timeout(120)
@pytest.mark.parametrize("persona", ["ardupilot", "px4"])
def test_mavproxy_loads_mission_fence_rally_lists_and_flies_auto(
    persona: str, tmp_path: Path
) -> None:
    mavproxy = Path(sys.executable).parent / "mavproxy.py"
    port = free_udp_base(1)
    with running_emulator(make_config(1, port, personas=(persona,), speedup=5.0)) as emu:
        v = emu.vehicles[0]
        wp, fence, rally = _files(tmp_path, *emu.telemetry.home_geo(v))
        log = tmp_path / "mavproxy.out"
        with log.open("w") as out:
            proc = subprocess.Popen(
                [sys.executable, str(mavproxy), f"--master=udpin:127.0.0.1:{port}", "--nowait",
                 f"--state-basedir={tmp_path}"],
                stdin=subprocess.PIPE, stdout=out, stderr=subprocess.STDOUT, cwd=tmp_path,
                text=True,
            )  # fmt: skip
            assert proc.stdin is not None
            stdin = proc.stdin

            def say(line: str, until: Callable[[], bool], seconds: float = 15.0) -> None:
                stdin.write(line + "\n")
                stdin.flush()
                assert _wait(until, seconds), (line, log.read_text()[-2000:])

            try:
                assert _wait(lambda: "online system 1" in log.read_text(), 20.0)
                say(f"wp load {wp}", lambda: "TYPE_MISSION: ACCEPTED" in log.read_text())
                say(f"fence load {fence}", lambda: "TYPE_FENCE: ACCEPTED" in log.read_text())
                say(f"rally load {rally}", lambda: "TYPE_RALLY: ACCEPTED" in log.read_text())
                say("wp list", lambda: "Saved 5 waypoints" in log.read_text())
                if persona == "ardupilot":
                    say("mode guided", lambda: v.mode.name == "GUIDED")
                    say("arm throttle", lambda: v.armed)
                    say("takeoff 10", lambda: float(v.fleet.alt[0]) > 3.0)
                    say("mode auto", lambda: v.mode.name == "AUTO")
                else:
                    say("long DO_SET_MODE 1 4 4", lambda: v.mode.name == "MISSION")
                    say("arm throttle", lambda: v.armed)
                # the mission is flown: the second waypoint becomes current
                assert _wait(lambda: v.mission_run.current >= 3, 30.0), log.read_text()[-2000:]
            finally:
                proc.kill()
                proc.wait(10)
        text = log.read_text()
    assert "Requesting 5 waypoints" in text
    assert [it.command for it in v.plans.mission.items] == [16, 22, 16, 16, 20]
    assert [it.command for it in v.plans.fence.items] == [5001] * 4
    assert [it.command for it in v.plans.rally.items] == [5100]
