"""The MAVLink frame checksum, shared by the emulator, the companion and signing.

CRC-16/MCRF4XX (pymavlink's ``x25crc``) over the frame's header and payload followed by the
message's CRC-extra byte. fastcrc's C function where it is installed (pymavlink uses it too),
called without a wrapper: every frame the emulator sends or decodes itself and every frame a
companion decodes itself goes through it.
"""

from __future__ import annotations

from pymavlink.generator import mavcrc


def _x25crc(data: bytes) -> int:
    return int(mavcrc.x25crc(data).crc)


frame_crc = mavcrc.mcrf4xx or _x25crc
