"""The link interface every MAVLink backend implements (pymavlink, MAVSDK)."""

from __future__ import annotations

import asyncio
from abc import ABC, abstractmethod
from typing import Literal

from companion.autopilots import Autopilot, FlightMode
from companion.guidance import Setpoint
from companion.link.messages import LinkEvent

SetpointKind = Literal["velocity", "position"]


class LinkError(RuntimeError):
    """The link cannot be opened or a command could not be delivered."""


class VehicleLink(ABC):
    """One vehicle over MAVLink: events in (``events``), commands and setpoints out.

    A backend parses what it receives into :mod:`companion.link.messages` events on
    ``events``; the mission reads nothing else. Commands return True when the vehicle
    accepted them and False when it refused or never answered.
    """

    events: asyncio.Queue[LinkEvent]
    autopilot: Autopilot | None
    """Set from the first HEARTBEAT of the vehicle."""

    @abstractmethod
    async def open(self) -> None:
        """Start listening / connect. Does not wait for the vehicle."""

    @abstractmethod
    async def close(self) -> None:
        """Release sockets and logs; safe to call twice."""

    async def configure_streams(self) -> None:
        """Ask the vehicle to stop streams the companion does not read (default: leave them)."""
        return

    async def reconnect(self) -> None:
        """Drop and re-open the transport after a link loss."""
        await self.close()
        await self.open()

    @abstractmethod
    def send_heartbeat(self) -> None:
        """One HEARTBEAT of the companion (MAV_TYPE_ONBOARD_CONTROLLER)."""

    @abstractmethod
    def send_setpoint(self, setpoint: Setpoint, kind: SetpointKind) -> None:
        """A velocity (with altitude-hold vd) or a position setpoint, local NED."""

    @abstractmethod
    async def set_mode(self, mode: FlightMode) -> bool:
        """Ask for a flight mode."""

    @abstractmethod
    async def arm(self) -> bool:
        """Arm the motors."""

    @abstractmethod
    async def takeoff(self, altitude: float) -> bool:
        """Climb to ``altitude`` m above home (autopilots that need a command for it)."""

    @abstractmethod
    async def set_sensor(self, index: int) -> bool:
        """Switch the payload sensor: parameter MDM_SENSOR (INT32), -1 = off."""

    async def __aenter__(self) -> VehicleLink:
        await self.open()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()
