"""`--connect serial:DEVICE:BAUD` against ArduCopter SITL's own serial port: SERIAL0 (served on
TCP by SITL) bridged by socat to a pseudo-terminal, as a flight controller's TELEM port on a
cable; the companion flies the search and lands, at 57600 and 921600 with each backend. What
the vehicle did is read on SERIAL1 (a second port of the autopilot), never from the
companion's log."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from tests import sitl
from tests.companion.sitl_observer import Observer
from tests.profile_files import levels, sensors, write_profile_with
from tests.waiting import wait_until

pytestmark = pytest.mark.skipif(
    shutil.which("socat") is None, reason="socat missing (apt-get install socat)"
)
SPEEDUP = 5.0


@pytest.fixture
def bridges() -> Iterator[list[subprocess.Popen[bytes]]]:
    procs: list[subprocess.Popen[bytes]] = []
    yield procs
    for p in procs:
        p.terminate()
        p.wait(timeout=10)


@pytest.mark.parametrize(
    ("backend", "baud"),
    [("pymavlink", 57600), ("pymavlink", 921600), ("mavsdk", 57600), ("mavsdk", 921600)],
)
def test_a_search_over_arducopters_serial_port_flies_and_lands(
    arducopter: Callable[..., sitl.SitlInstance],
    bridges: list[subprocess.Popen[bytes]],
    tmp_path: Path,
    backend: str,
    baud: int,
) -> None:
    index = sitl.free_index("arducopter")
    inst = arducopter(speedup=SPEEDUP, index=index)
    device = tmp_path / "ttyTELEM"
    serial0 = 5760 + 10 * index
    with (tmp_path / "socat.log").open("ab") as log:
        bridge = subprocess.Popen(
            ["socat", f"pty,raw,echo=0,link={device}",
             f"tcp:127.0.0.1:{serial0},retry=60,interval=0.5"],
            stdout=log, stderr=subprocess.STDOUT,
        )  # fmt: skip
    bridges.append(bridge)
    wait_until(device.exists, 20, f"socat's pty {device}")
    profile = write_profile_with(
        tmp_path / "sitl-small.yaml",
        "sitl-small",
        targets=[{"north": 1500.0, "east": 1500.0}],
        fleet={"vehicles": index + 1},
        sensors=sensors(300.0, 100.0),
        policy={"levels": levels(600.0, 300.0, 150.0)},
        mission={"duration": 600.0},
    )
    observer = Observer(inst.observer_url, inst.sysid)
    out = tmp_path / "run"
    out.mkdir()
    try:
        done = subprocess.run(
            [sys.executable, "-m", "companion.cli", "run", "--profile", str(profile),
             "--vehicle", str(index), "--connect", f"serial:{device}:{baud}",
             "--backend", backend, "--log-dir", str(out), "--duration", "60",
             "--land-wait", "600", "--flight-log-wait", "0", "--end-action", "land", "--no-map"],
            capture_output=True, text=True, timeout=600, check=False,
            env=dict(os.environ, PYTHONUNBUFFERED="1"),
        )  # fmt: skip
        seen = observer.snapshot()
    finally:
        observer.close()
    said = done.stdout[-2000:] + done.stderr[-3000:]
    assert done.returncode == 0, said + inst.log()[-1500:]
    assert f"{device}:{baud}" in done.stdout + done.stderr  # the link as opened
    assert "Traceback" not in done.stderr
    assert seen.armed_ever
    assert seen.max_alt > 20.0, f"climbed to {seen.max_alt:.1f} m"
    assert seen.distance > 200.0, f"flew {seen.distance:.0f} m"
    assert not seen.armed, "still armed"
    assert seen.alt < 1.0, f"ended {seen.alt:.1f} m up"
    print(
        f"ArduCopter SITL serial {backend} {baud}: flew {seen.distance:.0f} m, max altitude "
        f"{seen.max_alt:.1f} m, landed and disarmed (SERIAL1)"
    )
