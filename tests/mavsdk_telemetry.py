"""What MAVSDK's telemetry plugin reads from a vehicle on the ground: the first value of each
subscription a ground station shows (tests/sim_vehicle_stub/test_svs_mavsdk_telemetry.py)."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator, Callable
from typing import Any

from mavsdk.asyncio import Configuration, Mavsdk
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync

from tests.mavsdk_flights import autopilot

SUBSCRIPTIONS = (
    "health",
    "home",
    "position",
    "gps_info",
    "battery",
    "flight_mode",
    "armed",
    "in_air",
    "landed_state",
    "attitude_euler",
    "velocity_ned",
    "fixedwing_metrics",
    "rc_status",
)
"""MAVSDK subscriptions (fixedwing_metrics is VFR_HUD, rc_status RC_CHANNELS)."""
WAIT_FOR: dict[str, Callable[[Any], bool]] = {
    "health": lambda h: h.is_global_position_ok and h.is_home_position_ok,
}
"""Subscriptions read until a value passes (health is not OK in its first message)."""


def _any(_: Any) -> bool:
    return True


async def _first(stream: AsyncIterator[Any], seconds: float, ok: Callable[[Any], bool]) -> Any:
    async def first() -> Any:
        async for value in stream:
            if ok(value):
                return value
        return None

    try:
        return await asyncio.wait_for(first(), seconds)
    except TimeoutError:
        return None


async def first_values(url: str, seconds: float = 10.0) -> dict[str, Any]:
    """Each of SUBSCRIPTIONS' first value, or first passing WAIT_FOR (None: nothing did in
    ``seconds`` wall s)."""
    async with Mavsdk(Configuration.create_manual(245, 190, True)) as mavsdk:
        system = await autopilot(mavsdk, url)
        tel = TelemetryAsync(system)
        names = list(SUBSCRIPTIONS)
        got = await asyncio.gather(
            *(
                _first(getattr(tel, f"subscribe_{n}")(), seconds, WAIT_FOR.get(n, _any))
                for n in names
            )
        )
    return dict(zip(names, got, strict=True))
