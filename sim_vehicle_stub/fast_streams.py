"""The 10 Hz streams (GLOBAL_POSITION_INT, LOCAL_POSITION_NED, ATTITUDE) and the sensor messages
packed for every vehicle at once with numpy, byte-identical to pymavlink's encoding.

These are most of what the emulator sends; packing them per vehicle through message objects was
the main cost at high speed-ups.
"""

from __future__ import annotations

import struct

import numpy as np

from sim_vehicle_stub.fleet import Fleet
from sim_vehicle_stub.mavlink import dialect as d

GPI, LPN, ATT = (
    d.MAVLINK_MSG_ID_GLOBAL_POSITION_INT,
    d.MAVLINK_MSG_ID_LOCAL_POSITION_NED,
    d.MAVLINK_MSG_ID_ATTITUDE,
)
NVF, DEBUG_VECT = d.MAVLINK_MSG_ID_NAMED_VALUE_FLOAT, d.MAVLINK_MSG_ID_DEBUG_VECT
CRC_EXTRA = {k: d.mavlink_map[k].crc_extra for k in (GPI, LPN, ATT, NVF, DEBUG_VECT)}

_GPI = np.dtype(
    [("t", "<u4"), ("lat", "<i4"), ("lon", "<i4"), ("alt", "<i4"), ("rel", "<i4"),
     ("vx", "<i2"), ("vy", "<i2"), ("vz", "<i2"), ("hdg", "<u2")]
)  # fmt: skip
_LPN = np.dtype([("t", "<u4")] + [(k, "<f4") for k in ("x", "y", "z", "vx", "vy", "vz")])
_ATT = np.dtype([("t", "<u4")] + [(k, "<f4") for k in ("r", "p", "y", "rs", "ps", "ys")])
_NVF = struct.Struct("<If10s")
_DVEC = struct.Struct("<Qfff10s")


def _rows(arr: np.ndarray) -> list[bytes]:
    buf, size = arr.tobytes(), arr.dtype.itemsize
    return [buf[i : i + size].rstrip(b"\x00") or b"\x00" for i in range(0, len(buf), size)]


def position_payloads(
    fleet: Fleet,
    boot_ms: int,
    lat: np.ndarray,
    lon: np.ndarray,
    amsl: np.ndarray,
    roll: np.ndarray,
    pitch: np.ndarray,
) -> dict[int, list[bytes]]:
    """Payloads of the three position/attitude messages, one per vehicle (trailing zeros cut)."""
    n = len(fleet)
    gpi = np.zeros(n, _GPI)
    gpi["t"] = boot_ms
    gpi["lat"] = (lat * 1e7).astype(np.int32)
    gpi["lon"] = (lon * 1e7).astype(np.int32)
    gpi["alt"] = (amsl * 1000).astype(np.int32)
    gpi["rel"] = (fleet.alt * 1000).astype(np.int32)
    gpi["vx"] = (fleet.vel[:, 0] * 100).astype(np.int16)
    gpi["vy"] = (fleet.vel[:, 1] * 100).astype(np.int16)
    gpi["vz"] = (-fleet.vz * 100).astype(np.int16)
    gpi["hdg"] = (np.mod(np.degrees(fleet.yaw), 360.0) * 100).astype(np.uint16)
    lpn = np.zeros(n, _LPN)
    lpn["t"] = boot_ms
    lpn["x"], lpn["y"], lpn["z"] = fleet.pos[:, 0], fleet.pos[:, 1], -fleet.alt
    lpn["vx"], lpn["vy"], lpn["vz"] = fleet.vel[:, 0], fleet.vel[:, 1], -fleet.vz
    att = np.zeros(n, _ATT)
    att["t"] = boot_ms
    att["r"], att["p"] = roll, pitch
    att["y"] = np.remainder(fleet.yaw + np.pi, 2 * np.pi) - np.pi
    return {GPI: _rows(gpi), LPN: _rows(lpn), ATT: _rows(att)}


def signal_payload(boot_ms: int, value: float) -> bytes:
    """NAMED_VALUE_FLOAT "SENS_SIG"."""
    return _NVF.pack(boot_ms, value, b"SENS_SIG").rstrip(b"\x00") or b"\x00"


def contact_payload(name: bytes, usec: int, north: float, east: float, strength: float) -> bytes:
    """DEBUG_VECT "DET"/"CNF" with x north, y east, z signal strength."""
    return _DVEC.pack(usec, north, east, strength, name).rstrip(b"\x00") or b"\x00"
