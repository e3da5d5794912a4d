"""The horizontal speed limit: DO_CHANGE_SPEED, then the autopilot's own parameter (a part of
every link), and the parameter probe it and the sensor switch share."""

from __future__ import annotations

from typing import Protocol

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.autopilots import Autopilot
from companion.link.outcome import CommandResult


class _Tuner(Protocol):
    autopilot: Autopilot | None
    _param_known: dict[str, bool]

    async def command_long(self, command: int, *params: float) -> CommandResult: ...

    async def read_param(self, name: str) -> float | None: ...

    async def set_param(self, name: str, value: float, param_type: int) -> float | None: ...


class SpeedPolicy:
    """The speed limit and parameter probes of a :class:`~companion.link.base.VehicleLink`."""

    async def has_param(self: _Tuner, name: str) -> bool:
        """Whether the vehicle answers PARAM_REQUEST_READ for ``name`` (asked once)."""
        known = self._param_known.get(name)
        if known is None:
            known = await self.read_param(name) is not None
            self._param_known[name] = known
        return known

    async def set_speed(self: _Tuner, speed: float) -> str:
        """Set the horizontal speed limit to ``speed`` m/s: DO_CHANGE_SPEED, then the
        autopilot's own parameter (read, raised if lower, read back). Returns what the vehicle
        now keeps, one line, naming a cap below ``speed``."""
        ap = self.autopilot
        result = await self.command_long(
            mavlink2.MAV_CMD_DO_CHANGE_SPEED,
            1.0,
            speed,
            -1.0,  # 1 = ground speed; -1 = throttle as is
        )
        line = f"DO_CHANGE_SPEED {speed:g} m/s {result.describe()}"
        if ap is None or ap.speed_param is None:
            return line
        name, scale = ap.speed_param
        value = await self.read_param(name)
        if value is None:
            return f"{line}; {name} not readable"
        if value / scale < speed - 1e-6:
            echoed = await self.set_param(name, speed * scale, mavlink2.MAV_PARAM_TYPE_REAL32)
            if echoed is None:
                return f"{line}; {name} {value / scale:g} m/s, raising it got no answer"
            value = echoed
        kept = value / scale
        if kept < speed - 1e-6:
            return f"{line}; vehicle caps at {kept:g} m/s ({name}), profile asks {speed:g}"
        return f"{line}; {name} {kept:g} m/s"
