"""An autopilot's parameter table and the two ways MAVLink carries a parameter's value."""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from enum import IntEnum


class ParamType(IntEnum):
    """MAV_PARAM_TYPE values used by the personas."""

    INT8 = 2
    INT16 = 4
    INT32 = 6
    REAL32 = 9


@dataclass(frozen=True)
class ParamSpec:
    """One parameter's name, type, default and accepted range."""

    name: str
    """At most 16 characters, as PARAM_VALUE.param_id."""
    default: float
    kind: ParamType = ParamType.REAL32
    low: float = -math.inf
    high: float = math.inf
    doc: str = ""


def bytewise_to_float(value: int) -> float:
    """PX4's encoding: the INT32's four bytes reinterpreted as the float field."""
    return float(struct.unpack("<f", struct.pack("<i", int(value)))[0])


def float_to_bytewise(value: float) -> int:
    """Inverse of :func:`bytewise_to_float`."""
    return int(struct.unpack("<i", struct.pack("<f", value))[0])


class ParamTable:
    """Ordered, typed parameter values of one vehicle."""

    def __init__(self, specs: list[ParamSpec], *, bytewise_ints: bool) -> None:
        self._specs = {s.name: s for s in specs}
        self._names = [s.name for s in specs]
        self._values = {s.name: float(s.default) for s in specs}
        self.bytewise_ints = bytewise_ints
        """True for PX4 (integers bytewise in the float field), False for ArduPilot (cast)."""

    def __len__(self) -> int:
        return len(self._names)

    def __contains__(self, name: object) -> bool:
        return name in self._values

    def names(self) -> list[str]:
        return list(self._names)

    def index(self, name: str) -> int:
        return self._names.index(name)

    def name_at(self, index: int) -> str | None:
        return self._names[index] if 0 <= index < len(self._names) else None

    def spec(self, name: str) -> ParamSpec:
        return self._specs[name]

    def get(self, name: str) -> float:
        return self._values[name]

    def set(self, name: str, value: float) -> None:
        """Set a value already decoded to a number; raises ValueError when out of range."""
        spec = self._specs[name]
        if not math.isfinite(value) or not spec.low <= value <= spec.high:
            raise ValueError(f"{name}={value} outside [{spec.low}, {spec.high}]")
        if spec.kind != ParamType.REAL32:
            value = float(round(value))
        self._values[name] = value

    def wire_value(self, name: str) -> float:
        """The float that PARAM_VALUE carries for this parameter."""
        value = self._values[name]
        if self.bytewise_ints and self._specs[name].kind != ParamType.REAL32:
            return bytewise_to_float(int(value))
        return value

    def decode(self, name: str, wire: float) -> float:
        """The number a PARAM_SET meant.

        Integers are read bytewise on PX4; a float-cast integer is accepted too when the bytewise
        reading is out of range and the cast one is not, so either client convention works.
        """
        spec = self._specs[name]
        if spec.kind == ParamType.REAL32 or not self.bytewise_ints:
            return float(wire)
        as_int = float(float_to_bytewise(wire))
        if spec.low <= as_int <= spec.high:
            return as_int
        if math.isfinite(wire) and wire == round(wire) and spec.low <= wire <= spec.high:
            return float(wire)
        return as_int
