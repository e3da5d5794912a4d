"""MAVLink encoding for one vehicle: its own system id, component 1 and sequence counter."""

from __future__ import annotations

from typing import Any

from sim_vehicle_stub.mavlink import dialect


class Encoder:
    """Packs messages as system ``sysid``, component 1, numbering them in sequence."""

    def __init__(self, sysid: int, compid: int = 1) -> None:
        self.mav = dialect.MAVLink(None, srcSystem=sysid, srcComponent=compid)

    def pack(self, msg: Any) -> bytes:
        data: bytes = msg.pack(self.mav)
        self.mav.seq = (self.mav.seq + 1) % 256
        return data
