"""The 10 Hz streams (GLOBAL_POSITION_INT, LOCAL_POSITION_NED, ATTITUDE) and the sensor messages
packed for every vehicle at once with numpy, and the 1 Hz streams packed from their fields by a
precomputed layout; all byte-identical to pymavlink's encoding.

These are most of what the emulator sends; packing them per vehicle through message objects was
the main cost at high speed-ups.
"""

from __future__ import annotations

import inspect
import operator
import struct
from collections.abc import Sequence
from typing import Any

import numpy as np

from mavlink_wire.frames import cut
from sim_vehicle_stub.fleet_kinematics import Fleet
from sim_vehicle_stub.mavlink import dialect as d

GPI, LPN, ATT = (
    d.MAVLINK_MSG_ID_GLOBAL_POSITION_INT,
    d.MAVLINK_MSG_ID_LOCAL_POSITION_NED,
    d.MAVLINK_MSG_ID_ATTITUDE,
)
POSITION_STREAMS = frozenset((GPI, LPN, ATT))
"""The 10 Hz streams packed for the whole fleet at once."""
NVF, DEBUG_VECT = d.MAVLINK_MSG_ID_NAMED_VALUE_FLOAT, d.MAVLINK_MSG_ID_DEBUG_VECT

_NVF = struct.Struct("<If10s")
_DVEC = struct.Struct("<Qfff10s")


def _rows(arr: np.ndarray) -> list[bytes]:
    buf, size = arr.tobytes(), arr.itemsize * arr.shape[1]
    return [cut(buf[i : i + size]) for i in range(0, len(buf), size)]


# Each message is a row of one plain array whose columns are its fields in wire order (a 4-byte
# column holding the two 2-byte fields that share it), filled a few columns per operation; the
# casts are numpy's astype casts.


def gpi_rows(
    fleet: Fleet, boot_ms: int, lat: np.ndarray, lon: np.ndarray, amsl: np.ndarray
) -> list[bytes]:
    """GLOBAL_POSITION_INT payloads: time_boot_ms u4, lat, lon, alt, relative_alt i4, vx, vy,
    vz i2, hdg u2."""
    gpi = np.empty((len(fleet), 7), np.int32)
    gpi.view(np.uint32)[:, 0] = boot_ms
    gpi[:, 1] = lat * 1e7
    gpi[:, 2] = lon * 1e7
    gpi[:, 3] = amsl * 1000
    gpi[:, 4] = fleet.alt * 1000
    short = gpi.view(np.int16)
    short[:, 10:12] = fleet.vel * 100
    short[:, 12] = -fleet.vz * 100
    gpi.view(np.uint16)[:, 13] = np.mod(np.degrees(fleet.yaw), 360.0) * 100
    return _rows(gpi)


def lpn_rows(fleet: Fleet, boot_ms: int, origins: np.ndarray) -> list[bytes]:
    """LOCAL_POSITION_NED payloads: time_boot_ms u4, x, y, z, vx, vy, vz f4 (z and vz down);
    x, y from each vehicle's local origin (``origins``, (n, 2) in the profile's frame)."""
    lpn = np.empty((len(fleet), 7), np.float32)
    lpn.view(np.uint32)[:, 0] = boot_ms
    lpn[:, 1:3] = fleet.pos - origins
    lpn[:, 3] = -fleet.alt
    lpn[:, 4:6] = fleet.vel
    lpn[:, 6] = -fleet.vz
    return _rows(lpn)


def att_rows(fleet: Fleet, boot_ms: int, roll: np.ndarray, pitch: np.ndarray) -> list[bytes]:
    """ATTITUDE payloads: time_boot_ms u4, roll, pitch, yaw, and the three rates (0) f4."""
    att = np.zeros((len(fleet), 7), np.float32)
    att.view(np.uint32)[:, 0] = boot_ms
    att[:, 1] = roll
    att[:, 2] = pitch
    att[:, 3] = np.remainder(fleet.yaw + np.pi, 2 * np.pi) - np.pi
    return _rows(att)


def signal_payload(boot_ms: int, value: float) -> bytes:
    """NAMED_VALUE_FLOAT "SENS_SIG"."""
    return cut(_NVF.pack(boot_ms, value, b"SENS_SIG"))


def contact_payload(name: bytes, usec: int, north: float, east: float, strength: float) -> bytes:
    """DEBUG_VECT "DET"/"CNF" with x north, y east, z signal strength."""
    return cut(_DVEC.pack(usec, north, east, strength, name))


class WireLayout:
    """Where a message's constructor arguments lie in its MAVLink 2 payload, so the payload is
    one struct.pack without a pymavlink message object (arguments left out take the
    constructor's defaults, as the object would)."""

    def __init__(self, cls: Any) -> None:
        self.msg_id: int = cls.id
        self._struct: struct.Struct = cls.unpacker
        params = list(inspect.signature(cls.__init__).parameters.values())[1:]
        self._defaults = tuple(p.default for p in params)
        names: list[str] = cls.fieldnames
        order = [names.index(f) for f in cls.ordered_fieldnames]
        self._pick = operator.itemgetter(*order)
        lengths: list[int] = list(cls.array_lengths)
        self._arrays = lengths if any(lengths) else []
        """Array length of each field in wire order (0: a scalar); empty without arrays."""

    def payload(self, args: Sequence[Any]) -> bytes:
        """The payload of ``cls(*args)``, trailing zeros cut."""
        values = self._pick(tuple(args) + self._defaults[len(args) :])
        if self._arrays:
            flat: list[Any] = []
            for value, n in zip(values, self._arrays, strict=True):
                if n:
                    flat.extend(value)
                else:
                    flat.append(value)
            values = flat
        return cut(self._struct.pack(*values))
