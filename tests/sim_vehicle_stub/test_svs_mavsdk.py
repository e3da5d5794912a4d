"""MAVSDK 4 (mavsdk.asyncio) flies each of 12 emulated PX4 vehicles over real UDP: health OK, arm,
takeoff, offboard, velocity and position setpoints; the response is the tau-lag model."""

from __future__ import annotations

import asyncio
import logging
import math
from collections import defaultdict
from typing import Any

import pytest
from mavsdk.asyncio import Configuration, Mavsdk
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.offboard import OffboardAsync, PositionNedYaw, VelocityNedYaw
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync

from sim_vehicle_stub.mavlink import dialect
from tests.emulator_harness import (
    TAU,
    fitted_tau,
    free_udp_base,
    make_config,
    running_emulator,
    step_samples,
)

logger = logging.getLogger(__name__)
N = 12
TAU_TOLERANCE = 0.02
SETTLE_TOLERANCE = 1.0


class GcsListener(asyncio.DatagramProtocol):
    """Collects LOCAL_POSITION_NED of every vehicle from the emulator's ground-station output."""

    def __init__(self) -> None:
        self.parser = dialect.MAVLink(None)
        self.log: dict[int, list[Any]] = defaultdict(list)

    def datagram_received(self, data: bytes, addr: tuple[str, int]) -> None:
        for msg in self.parser.parse_buffer(data) or []:
            if msg.get_type() == "LOCAL_POSITION_NED":
                self.log[msg.get_srcSystem()].append(msg)


async def _systems(mavsdk: Mavsdk) -> dict[int, Any]:
    for _ in range(100):
        found = {}
        for s in await mavsdk.get_systems():
            if await s.has_autopilot():
                found[await s.get_system_id()] = s
        if len(found) == N:
            return found
        await asyncio.sleep(0.1)
    raise AssertionError(f"only {len(found)} of {N} vehicles discovered")


async def _fly(sysid: int, system: Any, gcs: GcsListener) -> None:
    tel, act, off = TelemetryAsync(system), ActionAsync(system), OffboardAsync(system)
    async for health in tel.subscribe_health():
        if health.is_global_position_ok and health.is_home_position_ok and health.is_armable:
            break
    await act.set_takeoff_altitude(8.0 + sysid)
    await act.arm()
    await act.takeoff()
    async for pos in tel.subscribe_position():
        if pos.relative_altitude_m > 7.7 + sysid:
            break
    await off.set_velocity_ned(VelocityNedYaw(0.0, 0.0, 0.0, 0.0))
    await off.start()
    vn, ve = 5.0 + sysid * 0.5, -3.0
    log = gcs.log[sysid]
    mark = len(log)
    await off.set_velocity_ned(VelocityNedYaw(vn, ve, 0.0, 0.0))
    await asyncio.sleep(1.2)
    seen = log[mark:]
    assert seen[-1].vx == pytest.approx(vn, abs=0.05)
    assert seen[-1].vy == pytest.approx(ve, abs=0.05)
    for axis, target in (("vx", vn), ("vy", ve)):
        tau = fitted_tau(step_samples(seen, axis, target), target)
        logger.info("vehicle %d %s step to %.1f m/s: fitted tau %.4f s", sysid, axis, target, tau)
        assert tau == pytest.approx(TAU, abs=TAU_TOLERANCE), (sysid, axis)
    here = log[-1]
    goal = (here.x - 80.0, here.y + 40.0, -(10.0 + sysid))
    await off.set_position_ned(PositionNedYaw(*goal, 0.0))
    await asyncio.sleep(2.0)
    last = log[-1]
    err = math.hypot(last.x - goal[0], last.y - goal[1])
    logger.info("vehicle %d position error %.3f m", sysid, err)
    assert math.hypot(last.x - goal[0], last.y - goal[1]) < SETTLE_TOLERANCE
    assert last.z == pytest.approx(goal[2], abs=SETTLE_TOLERANCE)
    await off.stop()


@pytest.mark.timeout(120)
def test_mavsdk_connects_to_12_vehicles_and_flies_offboard_velocity_and_position() -> None:
    # The vehicles' own ports in a probed range too: bound to port 0, one could land on a port
    # MAVSDK is about to listen on (CI rehearsal: "Connection failed: BIND_ERROR").
    base = free_udp_base(N + 1, gap=N + 1)
    gcs_port = base + N  # the emulator's ground-station output
    cfg = make_config(N, base, gcs=True, gcs_port=gcs_port, bind_port_base=base + N + 1)

    async def main() -> None:
        loop = asyncio.get_running_loop()
        transport, gcs = await loop.create_datagram_endpoint(
            GcsListener, local_addr=("127.0.0.1", gcs_port)
        )
        try:
            async with Mavsdk(Configuration.create_manual(245, 190, True)) as mavsdk:
                for i in range(N):
                    await mavsdk.add_any_connection(f"udpin://127.0.0.1:{base + i}")
                systems = await _systems(mavsdk)
                await asyncio.wait_for(
                    asyncio.gather(*(_fly(i, s, gcs) for i, s in systems.items())), 90
                )
        finally:
            transport.close()

    with running_emulator(cfg) as emu:
        asyncio.run(main())
        modes = [v.mode.name for v in emu.vehicles]
        assert all(v.armed for v in emu.vehicles)
        assert modes == ["HOLD"] * N  # offboard.stop() -> Hold, as on PX4
