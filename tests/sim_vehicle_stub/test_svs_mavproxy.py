"""MAVProxy (headless) routes one emulated vehicle to a MAVSDK client, which arms and takes off.

MAVProxy is a Python program that decodes every packet it routes; on a loaded 2-core host it gets
a small share of a core, and what it needs decides whether the client hears the vehicle in time
(docs/companion.md "Sharing the UART"): about 0.5 s of CPU to start, then, at the emulator's
speed-up of 5 (200 datagrams/s) with its telemetry log on, 17 % of a core; held to 5 % its
parameter replies came too late and MAVSDK's `set_takeoff_altitude` failed. So the vehicle flies
in real time (42 datagrams/s, as a real vehicle sends), MAVProxy runs as the project's splitter
unit runs it (`--no-state`, no telemetry log: 4 % of a core), and the client's waits start once
MAVProxy forwards."""

from __future__ import annotations

import asyncio
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from mavsdk.asyncio import Configuration, Mavsdk
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync

from tests.emulator_harness import free_udp_base, make_config, running_emulator


def _wait_forwarded(port: int, proc: subprocess.Popen[bytes], log: Path, wait_s: float) -> None:
    """Until MAVProxy forwards the vehicle's packets to ``port``: its start-up (imports, 21
    modules) is not what the test is about, so the client's own waits start only once the route
    carries packets."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", port))
        sock.settimeout(1.0)
        end = time.monotonic() + wait_s
        while time.monotonic() < end:
            if proc.poll() is not None:
                pytest.fail(f"MAVProxy exited {proc.returncode}: {log.read_text()[-2000:]}")
            try:
                if sock.recv(1024):
                    return
            except TimeoutError:
                continue
    pytest.fail(f"MAVProxy forwarded nothing within {wait_s:g} s: {log.read_text()[-2000:]}")


@pytest.mark.timeout(240)
def test_mavproxy_routes_a_vehicle_to_mavsdk_which_arms_and_takes_off(tmp_path: Path) -> None:
    mavproxy = Path(sys.executable).parent / "mavproxy.py"
    vehicle_port = free_udp_base(2)  # the emulator sends to it; MAVProxy forwards to the next
    client_port = vehicle_port + 1
    cmd = [
        sys.executable,
        str(mavproxy),
        f"--master=udpin:127.0.0.1:{vehicle_port}",
        "--daemon",
        f"--out=udp:127.0.0.1:{client_port}",
        "--no-state",
        "--nowait",
    ]

    async def client() -> float:
        async with Mavsdk(Configuration.create_manual(245, 190, True)) as mavsdk:
            await mavsdk.add_any_connection(f"udpin://127.0.0.1:{client_port}")
            system = await mavsdk.first_autopilot(timeout_s=30)
            assert system is not None
            assert await system.get_system_id() == 1
            tel, act = TelemetryAsync(system), ActionAsync(system)
            async for health in tel.subscribe_health():
                if health.is_armable:
                    break
            await act.set_takeoff_altitude(6.0)
            await act.arm()
            await act.takeoff()
            async for pos in tel.subscribe_position():
                if pos.relative_altitude_m > 5.7:
                    return float(pos.relative_altitude_m)
        return 0.0

    log = tmp_path / "mavproxy.log"
    with running_emulator(make_config(1, vehicle_port, speedup=1.0)) as emu, log.open("wb") as out:
        proc = subprocess.Popen(
            cmd, stdin=subprocess.PIPE, stdout=out, stderr=subprocess.STDOUT, cwd=tmp_path
        )
        try:
            _wait_forwarded(client_port, proc, log, 150.0)
            altitude = asyncio.run(asyncio.wait_for(client(), 60))
        finally:
            proc.terminate()
            proc.wait(10)
        assert altitude > 5.7
        assert emu.vehicles[0].armed
        assert emu.nodes[0].stats.messages > 0
