"""docs/examples/mdm-splitter.service, MAVProxy sharing one serial link between the companion
and a ground station: its command as written (the device, the ports and the executable swapped
for the test's), on a pseudo-terminal bridged by socat to the emulator (a UART to a flight
controller). The companion flies the search over MAVProxy's UDP out and lands; the ground
station's out hears the vehicle meanwhile."""

from __future__ import annotations

import configparser
import shlex
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.companion.sitl_observer import Observer
from tests.emulator_harness import free_udp_base
from tests.vehicle_venv import BIND_OFFSET, fly
from tests.waiting import wait_until

EXAMPLE = Path(__file__).parents[2] / "docs" / "examples" / "mdm-splitter.service"
VENV = Path(sys.executable).parents[1]
pytestmark = [
    pytest.mark.usefixtures("fleet_processes"),
    pytest.mark.skipif(
        shutil.which("socat") is None, reason="socat missing (apt-get install socat)"
    ),
    pytest.mark.skipif(
        not (VENV / "bin" / "mavproxy.py").exists(),
        reason="MAVProxy missing (`pip install --no-deps mavproxy pyserial`)",
    ),
]


def splitter_argv(device: Path, companion_port: int, gcs_port: int) -> list[str]:
    """The example unit's ExecStart with the test's device, ports and MAVProxy."""
    unit = configparser.ConfigParser(strict=False, interpolation=None)
    unit.read_string(EXAMPLE.read_text())
    argv = shlex.split(unit["Service"]["ExecStart"])
    swap = {
        "--master=/dev/serial0": f"--master={device}",
        "--out=udp:127.0.0.1:14540": f"--out=udp:127.0.0.1:{companion_port}",
        "--out=udp:192.168.1.10:14550": f"--out=udp:127.0.0.1:{gcs_port}",
    }
    assert set(swap) <= set(argv), argv  # the example still says what the docs say
    return [str(VENV / "bin" / "mavproxy.py"), *(swap.get(a, a) for a in argv[1:])]


@pytest.fixture
def started(tmp_path: Path) -> Iterator[list[subprocess.Popen[bytes]]]:
    procs: list[subprocess.Popen[bytes]] = []
    yield procs
    for p in procs:
        p.terminate()
        p.wait(timeout=10)


def test_the_example_splitter_carries_the_companion_and_the_ground_station(
    tmp_path: Path, started: list[subprocess.Popen[bytes]]
) -> None:
    base = free_udp_base(4, gap=BIND_OFFSET)  # base: the emulator sends here (socat listens)
    companion_port, gcs_port = base + 1, base + 2
    device = tmp_path / "ttyFC"
    with (tmp_path / "socat.log").open("ab") as log:
        bridge = subprocess.Popen(
            ["socat", f"pty,raw,echo=0,link={device}",
             f"udp4-listen:{base},bind=127.0.0.1,reuseaddr"],
            stdout=log, stderr=subprocess.STDOUT,
        )  # fmt: skip
    started.append(bridge)
    wait_until(device.exists, 10, f"socat's pty {device}")
    with (tmp_path / "mavproxy.log").open("ab") as log:
        splitter = subprocess.Popen(
            splitter_argv(device, companion_port, gcs_port),
            stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, cwd=tmp_path,
        )  # fmt: skip
    started.append(splitter)
    gcs = Observer(f"udpin:127.0.0.1:{gcs_port}", sysid=1)
    try:
        flight = fly(
            VENV, tmp_path / "run", base=base, draw_map=False,
            link=("--connect", f"udpin:127.0.0.1:{companion_port}"),
        )  # fmt: skip
        heard = gcs.snapshot()
    finally:
        gcs.close()
    said = (flight.out / "companion-0.log").read_text()
    assert flight.returncode == 0, said[-3000:] + (tmp_path / "mavproxy.log").read_text()[-2000:]
    seen = flight.vehicle  # the emulator's own second link
    assert seen.armed_ever
    assert seen.distance > 200.0, f"flew {seen.distance:.0f} m"
    assert not seen.armed
    assert seen.alt < 1.0
    assert heard.armed_ever, "the ground station's out never heard the vehicle armed"
    assert heard.distance > 100.0, f"the ground station saw {heard.distance:.0f} m"
    print(
        f"splitter: companion flew {seen.distance:.0f} m, landed; ground station out heard "
        f"{heard.distance:.0f} m of it, modes {heard.modes}"
    )
