"""The vehicle's own geofence over the MAVLink mission protocol (mission_type FENCE): upload an
inclusion polygon, download what the vehicle stores.

ArduPilot takes inclusion-polygon vertices as MISSION_ITEM_INT with command
MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION, param1 = the polygon's vertex count, in a global
frame (libraries/GCS_MAVLink/MissionItemProtocol_Fence.cpp,
convert_MISSION_ITEM_INT_to_AC_PolyFenceItem) and stores lat/lon as 1e-7 degree integers, so
a read-back compares exactly.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.errors import CompanionError

FENCE = mavlink2.MAV_MISSION_TYPE_FENCE
VERTEX = mavlink2.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
MISSION_KINDS = frozenset(
    {"MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK", "MISSION_COUNT", "MISSION_ITEM_INT"}
)
"""Messages of the mission protocol the transfer reads."""

Vertex = tuple[int, int]
"""(lat, lon) in 1e-7 degrees, as the mission protocol carries them."""


class FenceTransferError(CompanionError, RuntimeError):
    """The vehicle did not take (or give) the fence; the message says at which step."""


class FenceRefusedError(FenceTransferError):
    """The vehicle refused the fence itself (too many items, a frame or command it does not
    take): trying again would not help."""


class FenceTransfer:
    """One upload or download at a time over ``send`` (encoded messages out) and ``inbox``
    (the link puts every mission-protocol message of the vehicle there)."""

    def __init__(
        self,
        mav: Any,
        send: Callable[[Any], None],
        target_system: int,
        *,
        timeout: float = 1.5,
        tries: int = 3,
    ) -> None:
        self._mav = mav
        self._send = send
        self._target = target_system
        self._timeout = timeout
        self._tries = tries
        self.inbox: asyncio.Queue[Any] = asyncio.Queue()

    async def upload(self, vertices: list[Vertex]) -> None:
        """Replace the vehicle's fence with one inclusion polygon. A transfer the vehicle
        drops (MAV_MISSION_ERROR or silence: PX4 answers MAV_MISSION_ERROR to an item that comes after it gave up waiting,
        or after it finished; it goes silent after its own time-out) is cancelled and started
        again from MISSION_COUNT, ``tries`` times in all; the error names every attempt."""
        failures: list[str] = []
        for _ in range(self._tries):
            try:
                await self._upload_once(vertices)
                return
            except FenceRefusedError:
                raise
            except FenceTransferError as exc:
                failures.append(str(exc))
            # End the vehicle's side of the transfer (PX4 goes idle on a cancel from its
            # partner), then start again.
            self._send(
                self._mav.mission_ack_encode(
                    self._target, 1, mavlink2.MAV_MISSION_OPERATION_CANCELLED, FENCE
                )
            )
            await asyncio.sleep(self._timeout / 3)
        raise FenceTransferError(f"{len(failures)} attempts failed: " + "; ".join(failures))

    async def _upload_once(self, vertices: list[Vertex]) -> None:
        n = len(vertices)
        count = self._mav.mission_count_encode(self._target, 1, n, FENCE)
        sent: set[int] = set()
        # The highest item the vehicle asked for: a request for an earlier one is a stale
        # repeat (PX4 repeats a request every 250 ms of its own clock) and is not answered, or
        # the item could reach the vehicle after the transfer ended (MAV_MISSION_ERROR).
        latest = -1
        count_tries = self._tries
        self._drain()
        self._send(count)
        while True:
            msg = await self._next(("MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK"))
            if msg is None:
                if sent or count_tries <= 1:
                    step = f"after item {max(sent)}" if sent else "to MISSION_COUNT"
                    raise FenceTransferError(f"no answer {step} (mission_type FENCE)")
                count_tries -= 1
                self._send(count)
                continue
            if msg.get_type() == "MISSION_ACK":
                if msg.type != mavlink2.MAV_MISSION_ACCEPTED:
                    name = mavlink2.enums["MAV_MISSION_RESULT"][msg.type].name
                    where = f"after item {max(sent)}" if sent else "to MISSION_COUNT"
                    error = (
                        FenceTransferError
                        if msg.type == mavlink2.MAV_MISSION_ERROR
                        else FenceRefusedError
                    )
                    raise error(f"fence refused {where}: {name}")
                if len(sent) < n:
                    raise FenceTransferError(f"accepted after {len(sent)} of {n} items")
                return
            seq = msg.seq
            if not 0 <= seq < n:
                raise FenceTransferError(f"vehicle asked for item {seq} of {n}")
            if seq < latest:
                continue
            latest = seq
            lat, lon = vertices[seq]
            self._send(
                self._mav.mission_item_int_encode(
                    self._target,
                    1,
                    seq,
                    mavlink2.MAV_FRAME_GLOBAL,
                    VERTEX,
                    0,
                    0,
                    float(n),
                    0.0,
                    0.0,
                    0.0,
                    lat,
                    lon,
                    0.0,
                    FENCE,
                )
            )
            sent.add(seq)

    async def download(self) -> list[Vertex]:
        """The inclusion-polygon vertices the vehicle stores (other fence items are named in
        the error: this companion uploads only one polygon)."""
        self._drain()
        ask = self._mav.mission_request_list_encode(self._target, 1, FENCE)
        msg = None
        for _ in range(self._tries):
            self._send(ask)
            msg = await self._next(("MISSION_COUNT",))
            if msg is not None:
                break
        if msg is None:
            raise FenceTransferError("no MISSION_COUNT for mission_type FENCE")
        out: list[Vertex] = []
        for seq in range(msg.count):
            item = None
            for _ in range(self._tries):
                self._send(self._mav.mission_request_int_encode(self._target, 1, seq, FENCE))
                item = await self._next(("MISSION_ITEM_INT",), seq=seq)
                if item is not None:
                    break
            if item is None:
                raise FenceTransferError(f"no fence item {seq} of {msg.count}")
            if item.command != VERTEX:
                raise FenceTransferError(
                    f"fence item {seq} is command {item.command}, not an inclusion-polygon vertex"
                )
            out.append((item.x, item.y))
        self._send(
            self._mav.mission_ack_encode(self._target, 1, mavlink2.MAV_MISSION_ACCEPTED, FENCE)
        )
        return out

    def _drain(self) -> None:
        while not self.inbox.empty():
            self.inbox.get_nowait()

    async def _next(self, kinds: tuple[str, ...], seq: int | None = None) -> Any:
        """The next fence message of one of ``kinds`` (and item ``seq``) within the timeout.
        What was queued by the deadline is still read: a busy event loop (this task waiting
        for its turn) must not read as a silent vehicle."""
        deadline = time.monotonic() + self._timeout
        late: int | None = None
        while True:
            if late is None and time.monotonic() >= deadline:
                late = self.inbox.qsize()
            if late is not None:
                if late == 0:
                    return None
                late -= 1
                msg = self.inbox.get_nowait()
            else:
                # asyncio.wait, not wait_for: on 3.11 wait_for can swallow a cancel
                getter = asyncio.ensure_future(self.inbox.get())
                done, _ = await asyncio.wait({getter}, timeout=deadline - time.monotonic())
                if not done:
                    getter.cancel()
                    continue
                msg = getter.result()
            if msg.get_type() not in kinds or getattr(msg, "mission_type", 0) != FENCE:
                continue
            if seq is not None and msg.seq != seq:
                continue
            return msg
