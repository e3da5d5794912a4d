"""The companion's fence upload (``FenceTransfer``) against stock PX4 SITL when the companion is
slow to answer, as under CI load: PX4 drops a transfer whose next item is late by its protocol
time-out (5 s of its own clock, 1 s wall at speed-up 5) and from then on is silent, and it answers
MAV_MISSION_ERROR to an item that comes after a transfer ended. The upload cancels and starts
again; what the vehicle stores is read on its other link (the GCS link), not the companion's."""

from __future__ import annotations

import asyncio
import os
import threading
import time
from collections.abc import Callable
from typing import Any

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil

from companion.link.fence_protocol import VERTEX, FenceTransfer
from tests import sitl
from tests.companion.sitl_observer import Observer

HOME = "47.405893,8.663214,440"
POLYGON = [(474000000, 86000000), (474100000, 86000000), (474100000, 86800000), (474000000, 86800000)]  # fmt: skip
STALL_S = 1.3
"""Longer than PX4's 5 s protocol time-out at speed-up 5 (measured: 1.0 s late is still taken,
1.2 s is dropped)."""


async def _upload_with_a_stall(url: str, sysid: int) -> list[tuple[int, int]]:
    conn = mavutil.mavlink_connection(url, source_system=sysid, source_component=191)
    assert conn.wait_heartbeat(timeout=60) is not None, "no PX4 heartbeat"
    loop = asyncio.get_running_loop()
    stop = threading.Event()
    stalled: list[int] = []

    def send(msg: Any) -> None:
        # The first item 2 goes out only after the event loop was busy elsewhere for STALL_S.
        if msg.get_type() == "MISSION_ITEM_INT" and msg.seq == 2 and not stalled:
            stalled.append(msg.seq)
            time.sleep(STALL_S)
        conn.mav.send(msg)

    transfer = FenceTransfer(conn.mav, send, sysid)

    def read() -> None:
        while not stop.is_set():
            msg = conn.recv_match(blocking=True, timeout=0.2)
            if msg is not None and msg.get_type().startswith("MISSION_"):
                loop.call_soon_threadsafe(transfer.inbox.put_nowait, msg)

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        await transfer.upload(POLYGON)
        assert stalled == [2]
        return await transfer.download()
    finally:
        stop.set()
        reader.join(timeout=2)
        conn.close()


def test_a_late_fence_item_is_uploaded_again_and_px4_holds_the_polygon(
    px4: Callable[..., sitl.SitlInstance],
) -> None:
    inst = px4(speedup=5, home=HOME)
    back = asyncio.run(_upload_with_a_stall(inst.companion_url, inst.sysid))
    assert back == POLYGON
    obs = Observer(inst.observer_url, inst.sysid)
    try:
        stored = obs.read_fence()
    finally:
        obs.close()
    assert stored == [(VERTEX, lat, lon) for lat, lon in POLYGON], stored
