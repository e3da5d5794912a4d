"""The payload sensor's switch, parameter MDM_SENSOR (a part of every link)."""

from __future__ import annotations

from typing import Protocol

from companion.link.outcome import CommandResult, denied


class _Switch(Protocol):
    async def has_param(self, name: str) -> bool: ...

    async def _set_sensor(self, index: int) -> CommandResult: ...


class SensorParameter:
    """The sensor switch of a :class:`~companion.link.base.VehicleLink`."""

    async def set_sensor(self: _Switch, index: int) -> CommandResult:
        """Switch the payload sensor: parameter MDM_SENSOR (INT32), -1 = off. Only where the
        vehicle has the parameter: otherwise denied at once, never a PARAM_SET loop."""
        if not await self.has_param("MDM_SENSOR"):
            return denied("MDM_SENSOR", "the vehicle has no MDM_SENSOR parameter")
        return await self._set_sensor(index)
