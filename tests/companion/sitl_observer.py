"""An independent view of a SITL vehicle: a second MAVLink connection (ArduCopter SERIAL1, PX4's
GCS link) that records what the vehicle did, so flight tests never judge from the companion's own
log. It asks for its own streams on its own link (per-link rates: the companion's are untouched)."""

from __future__ import annotations

import math
import os
import queue
import struct
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

_STREAMS = (
    mavlink2.MAVLINK_MSG_ID_GLOBAL_POSITION_INT,
    mavlink2.MAVLINK_MSG_ID_EXTENDED_SYS_STATE,
    mavlink2.MAVLINK_MSG_ID_SYS_STATUS,  # the battery: ArduCopter's SERIAL1 sends it only if asked
)
_VELOCITY_MASK = 3527
"""SET_POSITION_TARGET_LOCAL_NED type_mask: velocity only (ArduCopter and PX4 take it)."""
_PUSH_PERIOD_S = 0.05
"""Wall s between two setpoints of :meth:`Observer.push` (PX4's offboard link wants one at
least every COM_OF_LOSS_T vehicle s)."""


@dataclass
class Trace:
    """What the observer saw."""

    armed_ever: bool = False
    armed: bool = False
    mode: int = -1
    modes: list[int] = field(default_factory=list)
    """Custom modes in the order first seen after each change."""
    max_alt: float = 0.0
    alt: float = 0.0
    """Relative altitude, m."""
    distance: float = 0.0
    """Horizontal path length while airborne (> 1 m), m."""
    max_speed: float = 0.0
    """Horizontal ground speed, m/s."""
    landed_state: int = 0
    texts: list[str] = field(default_factory=list)
    last_position: tuple[float, float] | None = None
    track: list[tuple[float, float, float, int]] = field(default_factory=list)
    """(lat, lon, relative altitude, custom mode) of every position while airborne."""
    stamps: list[float] = field(default_factory=list)
    """The observer's monotonic wall time of each ``track`` entry (to line up several vehicles)."""
    boots: list[float] = field(default_factory=list)
    """The vehicle's own clock (``boot_s``) of each ``track`` entry."""
    boot_s: float = 0.0
    """The vehicle's own clock (time since boot of its latest position), s: runs at the SITL's
    speed-up as far as the host lets it, not at the nominal one."""
    battery: int = -1
    """SYS_STATUS battery_remaining, percent (-1: not known)."""
    mode_battery: list[int] = field(default_factory=list)
    """``battery`` when each of ``modes`` was first seen."""
    params: dict[str, float] = field(default_factory=dict)
    """Every PARAM_VALUE on this link (the echoes of :meth:`Observer.set_param`)."""
    mode_stamps: list[float] = field(default_factory=list)
    """The observer's monotonic wall time when each of ``modes`` was first seen."""
    mode_boots: list[float] = field(default_factory=list)
    """The vehicle's clock (``boot_s``) when each of ``modes`` was first seen."""


class Observer:
    """Reads ``url`` in a thread until ``close``; ``trace`` is updated live."""

    def __init__(self, url: str, sysid: int) -> None:
        self.url = url
        self.sysid = sysid
        self.trace = Trace()
        self._lock = threading.Lock()
        self._send_lock = threading.Lock()
        self._stop = threading.Event()
        self._mission: queue.Queue[Any] = queue.Queue()
        """Mission-protocol messages of the vehicle, for :meth:`read_fence`."""
        self._autopilot: int | None = None
        """MAV_AUTOPILOT of the vehicle's HEARTBEAT (PX4 sends integer parameters bytewise)."""
        self._params: queue.Queue[Any] = queue.Queue()
        """PARAM_VALUE messages of the vehicle, for :meth:`read_param`."""
        self._push: tuple[float, float, float] | None = None
        """The velocity (north, east, down; m/s) :meth:`push` streams, None: no setpoints."""
        self._conn = mavutil.mavlink_connection(url, source_system=250, source_component=190)
        self._thread = threading.Thread(target=self._run, name="observer", daemon=True)
        self._thread.start()

    def _ask_streams(self) -> None:
        for msg_id in _STREAMS:
            self._conn.mav.command_long_send(
                self.sysid,
                1,
                mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL,
                0,
                msg_id,
                100_000,
                0,
                0,
                0,
                0,
                0,
            )

    def _run(self) -> None:
        asked = beat = pushed = 0.0
        while not self._stop.is_set():
            now = time.monotonic()
            with self._send_lock:
                if self._push is not None and now - pushed >= _PUSH_PERIOD_S:
                    self._conn.mav.set_position_target_local_ned_send(
                        0, self.sysid, 1, mavlink2.MAV_FRAME_LOCAL_NED, _VELOCITY_MASK,
                        0, 0, 0, *self._push, 0, 0, 0, 0, 0,
                    )  # fmt: skip
                    pushed = now
                if now - beat > 1.0:  # a ground station, as the autopilot routes it
                    self._conn.mav.heartbeat_send(
                        mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0, 0
                    )
                    beat = now
                if now - asked > 5.0:  # again after a reboot or a lost request
                    self._ask_streams()
                    asked = now
            wait = 0.2 if self._push is None else _PUSH_PERIOD_S / 2
            msg = self._conn.recv_match(blocking=True, timeout=wait)
            if msg is None or msg.get_srcSystem() != self.sysid or msg.get_srcComponent() != 1:
                continue
            if msg.get_type() in ("MISSION_COUNT", "MISSION_ITEM_INT"):
                self._mission.put(msg)
            elif msg.get_type() == "PARAM_VALUE":
                self._params.put(msg)
            with self._lock:
                self._update(msg)

    def _update(self, msg: object) -> None:
        t = self.trace
        kind = msg.get_type()  # type: ignore[attr-defined]
        if kind == "HEARTBEAT" and msg.type != mavlink2.MAV_TYPE_GCS:  # type: ignore[attr-defined]
            self._autopilot = msg.autopilot  # type: ignore[attr-defined]
            t.armed = bool(msg.base_mode & mavlink2.MAV_MODE_FLAG_SAFETY_ARMED)  # type: ignore[attr-defined]
            t.armed_ever |= t.armed
            if msg.custom_mode != t.mode:  # type: ignore[attr-defined]
                t.mode = msg.custom_mode  # type: ignore[attr-defined]
                t.modes.append(t.mode)
                t.mode_battery.append(t.battery)
                t.mode_stamps.append(time.monotonic())
                t.mode_boots.append(t.boot_s)
        elif kind == "GLOBAL_POSITION_INT":
            t.boot_s = msg.time_boot_ms / 1000.0  # type: ignore[attr-defined]
            t.alt = msg.relative_alt / 1000.0  # type: ignore[attr-defined]
            t.max_alt = max(t.max_alt, t.alt)
            here = (msg.lat * 1e-7, msg.lon * 1e-7)  # type: ignore[attr-defined]
            if t.last_position is not None and t.alt > 1.0:
                t.distance += _metres(t.last_position, here)
                t.track.append((*here, t.alt, t.mode))
                t.stamps.append(time.monotonic())
                t.boots.append(t.boot_s)
            t.last_position = here
            t.max_speed = max(t.max_speed, math.hypot(msg.vx, msg.vy) / 100.0)  # type: ignore[attr-defined]
        elif kind == "PARAM_VALUE":
            name = msg.param_id  # type: ignore[attr-defined]
            t.params[name.decode() if isinstance(name, bytes) else name] = msg.param_value  # type: ignore[attr-defined]
        elif kind == "SYS_STATUS":
            t.battery = msg.battery_remaining  # type: ignore[attr-defined]
        elif kind == "EXTENDED_SYS_STATE":
            t.landed_state = msg.landed_state  # type: ignore[attr-defined]
        elif kind == "STATUSTEXT":
            t.texts.append(msg.text)  # type: ignore[attr-defined]

    def set_mode(self, main: float, sub: float = 0.0) -> None:
        """A pilot's mode change: DO_SET_MODE with the custom mode (ArduPilot) or PX4's main
        and sub mode."""
        with self._send_lock:
            self._conn.mav.command_long_send(
                self.sysid,
                1,
                mavlink2.MAV_CMD_DO_SET_MODE,
                0,
                mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                main,
                sub,
                0,
                0,
                0,
                0,
            )

    def command(self, command: int, *params: float) -> None:
        """COMMAND_LONG to the autopilot, as a ground station sends it (no ack awaited)."""
        full = [*params, *[0.0] * (7 - len(params))]
        with self._send_lock:
            self._conn.mav.command_long_send(self.sysid, 1, command, 0, *full)

    def push(self, velocity: tuple[float, float, float] | None) -> None:
        """Fly the vehicle from this link, as a second ground station could: a velocity
        setpoint (north, east, down; m/s, SET_POSITION_TARGET_LOCAL_NED) streamed every
        ``_PUSH_PERIOD_S`` wall s until ``push(None)``."""
        self._push = velocity

    def set_param(self, name: str, value: float) -> None:
        """PARAM_SET (REAL32), as a ground station sends it (the echo not awaited): the SITL's
        own SIM_* parameters change the simulated world mid-flight."""
        with self._send_lock:
            self._conn.mav.param_set_send(
                self.sysid, 1, name.encode(), value, mavlink2.MAV_PARAM_TYPE_REAL32
            )

    def read_fence(self) -> list[tuple[int, int, int]]:
        """The fence items the vehicle stores, (command, lat, lon) in 1e-7 degrees, downloaded
        on this link (MISSION_REQUEST_LIST with mission_type FENCE)."""
        fence = mavlink2.MAV_MISSION_TYPE_FENCE

        def ask(kind: str, send: Callable[[], None], seq: int = -1) -> Any:
            for _ in range(3):
                with self._send_lock:
                    send()
                deadline = time.monotonic() + 3.0
                while (left := deadline - time.monotonic()) > 0:
                    try:
                        msg = self._mission.get(timeout=left)
                    except queue.Empty:
                        break
                    wanted = msg.get_type() == kind and msg.mission_type == fence
                    if wanted and (seq < 0 or msg.seq == seq):
                        return msg
            raise AssertionError(f"observer: no {kind} {seq if seq >= 0 else ''} for the fence")

        mav = self._conn.mav
        count = ask("MISSION_COUNT", lambda: mav.mission_request_list_send(self.sysid, 1, fence))
        items = []
        for seq in range(count.count):

            def request(seq: int = seq) -> None:
                mav.mission_request_int_send(self.sysid, 1, seq, fence)

            item = ask("MISSION_ITEM_INT", request, seq)
            items.append((item.command, item.x, item.y))
        with self._send_lock:
            mav.mission_ack_send(self.sysid, 1, mavlink2.MAV_MISSION_ACCEPTED, fence)
        return items

    def read_param(self, name: str) -> float:
        """The vehicle's value of parameter ``name``, asked on this link (PARAM_REQUEST_READ);
        PX4's integers decoded from their bytes."""
        for _ in range(5):
            with self._send_lock:
                self._conn.mav.param_request_read_send(self.sysid, 1, name.encode(), -1)
            deadline = time.monotonic() + 2.0
            while (left := deadline - time.monotonic()) > 0:
                try:
                    msg = self._params.get(timeout=left)
                except queue.Empty:
                    break
                if msg.param_id != name:
                    continue
                value = float(msg.param_value)
                integer = msg.param_type != mavlink2.MAV_PARAM_TYPE_REAL32
                if integer and self._autopilot == mavlink2.MAV_AUTOPILOT_PX4:
                    return float(struct.unpack("<i", struct.pack("<f", value))[0])
                return value
        raise AssertionError(f"observer: no PARAM_VALUE {name}")

    def snapshot(self) -> Trace:
        with self._lock:
            t = self.trace
            return Trace(
                t.armed_ever,
                t.armed,
                t.mode,
                list(t.modes),
                t.max_alt,
                t.alt,
                t.distance,
                t.max_speed,
                t.landed_state,
                list(t.texts),
                t.last_position,
                list(t.track),
                list(t.stamps),
                list(t.boots),
                t.boot_s,
                t.battery,
                list(t.mode_battery),
                dict(t.params),
                list(t.mode_stamps),
                list(t.mode_boots),
            )

    def hold(
        self,
        vehicle_s: float,
        what: str,
        holds: Callable[[Trace], bool] = lambda _: True,
        *,
        wall_timeout: float = 120.0,
        context: Callable[[], str] | None = None,
    ) -> None:
        """Wait until the vehicle's own clock has run ``vehicle_s`` on (not a wall-clock sleep
        scaled by the nominal speed-up, which a loaded host's slower SITL would cut short),
        asserting ``holds`` of every snapshot meanwhile; ``what`` names it in a failure."""
        start = self.snapshot().boot_s
        deadline = time.monotonic() + wall_timeout
        while True:
            snap = self.snapshot()
            more = "" if context is None else f"\n{context()}"
            assert holds(snap), f"{what}: broken {snap.boot_s - start:.1f} vehicle s in{more}"
            if snap.boot_s - start >= vehicle_s:
                return
            assert time.monotonic() < deadline, (
                f"{what}: the vehicle's clock ran {snap.boot_s - start:.1f} of {vehicle_s:g} s "
                f"in {wall_timeout:g} s wall{more}"
            )
            time.sleep(0.05)

    def await_state(
        self,
        holds: Callable[[Trace], bool],
        vehicle_s: float,
        what: str,
        *,
        wall_timeout: float = 300.0,
        context: Callable[[], str] | None = None,
    ) -> Trace:
        """Wait until ``holds`` of a snapshot; fail once the vehicle's own clock ran
        ``vehicle_s`` without it (a loaded host's slower SITL gets its time, where a wall-clock
        bound scaled by the nominal speed-up ran out), or after ``wall_timeout`` wall s (a
        stalled SITL)."""
        start = self.snapshot().boot_s
        deadline = time.monotonic() + wall_timeout
        while True:
            snap = self.snapshot()
            if holds(snap):
                return snap
            ran = snap.boot_s - start
            if ran >= vehicle_s or time.monotonic() > deadline:
                more = "" if context is None else f"\n{context()}"
                raise AssertionError(
                    f"{what}: not seen in {ran:.1f} vehicle s ({vehicle_s:g} allowed; wall "
                    f"limit {wall_timeout:g} s){more}"
                )
            time.sleep(0.05)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        self._conn.close()


def _metres(a: tuple[float, float], b: tuple[float, float]) -> float:
    """Flat-earth distance, plenty for steps of a few metres."""
    north = math.radians(b[0] - a[0]) * 6_371_000.0
    east = math.radians(b[1] - a[1]) * 6_371_000.0 * math.cos(math.radians(a[0]))
    return math.hypot(north, east)
