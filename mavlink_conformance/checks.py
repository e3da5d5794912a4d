"""The checks, one function each, and :func:`run_checks` that runs them against an address.

Every check is safe on a disarmed vehicle on the ground and leaves it as it found it: no NaN or
out-of-range values (only with ``hostile``, which may crash an autopilot: ArduCopter SITL aborts
on a NaN takeoff), every stream rate, mode and parameter it changes is set back, and a closed
link stops the run at once. Rates are measured in bounded windows of the vehicle's own clock
(TIMESYNC gives its speed-up against wall time).
"""

from __future__ import annotations

import contextlib
import itertools
import logging
import math
import struct
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import pymap3d

from mavlink_conformance.session import LinkClosedError, Session, mavutil

log = logging.getLogger(__name__)
ml = mavutil.mavlink

PX4, ARDUPILOT = ml.MAV_AUTOPILOT_PX4, ml.MAV_AUTOPILOT_ARDUPILOTMEGA
_GPS_BIT, _PREARM_BIT = 0x20, 0x10000000
_STREAMS = ("GLOBAL_POSITION_INT", "LOCAL_POSITION_NED", "SYS_STATUS", "EXTENDED_SYS_STATE")
_UNKNOWN_COMMAND = 31999
_STREAM_HZ = 5.0
_RATE_TOLERANCE = 0.3
"""Relative error allowed between a measured stream rate and the rate asked for."""
_WINDOW = 3.0
"""Wall seconds of every rate measurement."""
_HEARTBEAT_HZ = (0.8, 2.5)
"""Heartbeat rates (vehicle clock) that pass: 1 Hz nominal, early beats on changes allowed."""
_PX4_SAFE_MODES = (0x3040000, 0x30000, 0x20000, 0x10000)  # HOLD, POSCTL, ALTCTL, MANUAL
_ARDUPILOT_SAFE_MODES = (2, 0)  # ALT_HOLD, STABILIZE: no position needed, fine disarmed
_FTP_OPEN_RO, _FTP_ACK, _FTP_NAK = 4, 128, 129


@dataclass(frozen=True)
class CheckResult:
    """The outcome of one check."""

    name: str
    passed: bool
    detail: str

    def line(self) -> str:
        return f"{'PASS' if self.passed else 'FAIL'}  {self.name:<22} {self.detail}"


Check = Callable[[Session], CheckResult]


def _measure_speed(s: Session) -> None:
    """The vehicle clock's speed against wall time, from two TIMESYNC answers 1 s apart."""
    samples = []
    for k in range(2):
        stamp = 1_000_000 + k
        sent = time.monotonic()
        s.mav.timesync_send(0, stamp)
        m = s.recv({"TIMESYNC"}, 2.0, lambda m, st=stamp: m.ts1 == st and m.tc1 != 0)
        if m is None:
            return
        samples.append(((sent + time.monotonic()) / 2, m.tc1 * 1e-9))
        if k == 0:
            s.collect(1.0)
    (w0, v0), (w1, v1) = samples
    if w1 > w0 and v1 > v0:
        s.speed = (v1 - v0) / (w1 - w0)


def _rate(stamps: list[float], s: Session) -> float:
    """Messages per vehicle second from wall arrival times within one window."""
    if len(stamps) < 2 or stamps[-1] <= stamps[0]:
        return 0.0
    return (len(stamps) - 1) / s.vehicle_seconds(stamps[0], stamps[-1])


def check_heartbeat(s: Session) -> CheckResult:
    hb = s.recv({"HEARTBEAT"}, s.timeout, lambda m: m.get_srcComponent() == 1)
    if hb is None:
        return CheckResult("heartbeat", False, f"no autopilot HEARTBEAT in {s.timeout:.0f} s")
    first = s.seen["HEARTBEAT"][-1][0]
    _measure_speed(s)
    s.collect(max(0.0, first + _WINDOW - time.monotonic()))
    # Every autopilot heartbeat from the first on, over a window of at least _WINDOW s.
    stamps = [t for t, m in s.seen["HEARTBEAT"] if t >= first and m.get_srcComponent() == 1]
    rate = _rate(stamps, s)
    problems = []
    if hb.type == ml.MAV_TYPE_GCS:
        problems.append("type is GCS")
    if hb.autopilot not in (PX4, ARDUPILOT):
        problems.append(f"autopilot {hb.autopilot} is neither PX4 (12) nor ArduPilot (3)")
    if not hb.base_mode & ml.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
        problems.append("CUSTOM_MODE_ENABLED not set")
    low, high = _HEARTBEAT_HZ
    if not low <= rate <= high:
        problems.append(f"rate {rate:.2f} Hz outside {low}-{high} Hz ({len(stamps)} in window)")
    detail = f"type {hb.type}, autopilot {hb.autopilot}, {rate:.2f} Hz, clock x{s.speed:.2f}"
    return CheckResult("heartbeat", not problems, "; ".join(problems) or detail)


def check_mavlink2(s: Session) -> CheckResult:
    ok = bool(s.mavlink2)
    detail = "MAVLink 2 frames" if ok else "MAVLink 1 only: MAVSDK and signing need MAVLink 2"
    return CheckResult("mavlink2", ok, detail)


def check_ids(s: Session) -> CheckResult:
    hb = s.heartbeat
    ok = hb is not None and 1 <= hb.get_srcSystem() <= 255 and hb.get_srcComponent() == 1
    detail = f"system {s.sysid}, component {hb.get_srcComponent() if hb else '-'}"
    return CheckResult("ids", ok, detail)


def mode_name(hb: Any) -> str | None:
    """The mode a heartbeat's custom_mode encodes, or None when it is not a known mode."""
    if hb.autopilot == PX4:
        main, sub = (hb.custom_mode >> 16) & 0xFF, (hb.custom_mode >> 24) & 0xFF
        if hb.custom_mode & 0xFFFF:
            return None
        for name, (_, m, sb) in mavutil.px4_map.items():
            if m == main and (sb == sub or (main != 4 and sub == 0)):
                return str(name)
        return None
    names = mavutil.mode_mapping_bynumber(hb.type) or {}
    name = names.get(hb.custom_mode)
    return None if name is None else str(name)


def check_mode_encoding(s: Session) -> CheckResult:
    hb = s.heartbeat
    name = mode_name(hb) if hb else None
    detail = f"custom_mode {hb.custom_mode:#x} = {name}" if hb else "no heartbeat"
    return CheckResult("mode_encoding", name is not None, detail)


def _set_interval(s: Session, msg_id: int, interval_us: float) -> int | None:
    ack = s.command(ml.MAV_CMD_SET_MESSAGE_INTERVAL, msg_id, interval_us)
    return None if ack is None else int(ack.result)


def check_streams(s: Session) -> CheckResult:
    """Ask for each stream at 5 Hz, measure it over a bounded window, then set it back (to the
    default rate if it was streaming before, off if not)."""
    before = {k for k in _STREAMS if s.seen.get(k)}
    problems = []
    for kind in _STREAMS:
        result = _set_interval(s, getattr(ml, f"MAVLINK_MSG_ID_{kind}"), 1e6 / _STREAM_HZ)
        if result != 0:
            problems.append(f"SET_MESSAGE_INTERVAL {kind}: result {result}")
    s.collect(0.5)  # let the new rates take over
    start = time.monotonic()
    s.collect(_WINDOW)
    rates = {k: _rate([t for t, _ in s.seen.get(k, []) if t >= start], s) for k in _STREAMS}
    for kind in _STREAMS:
        restore = 0 if kind in before else -1
        result = _set_interval(s, getattr(ml, f"MAVLINK_MSG_ID_{kind}"), restore)
        if result != 0:
            problems.append(f"restoring {kind}: result {result}")
    for kind, rate in rates.items():
        if abs(rate - _STREAM_HZ) > _RATE_TOLERANCE * _STREAM_HZ:
            problems.append(f"{kind} at {rate:.2f} Hz, asked {_STREAM_HZ:.0f} Hz")
    got = ", ".join(f"{k} {r:.2f} Hz" for k, r in rates.items())
    status = s.seen.get("SYS_STATUS")
    if status:
        m = status[-1][1]
        bits = m.onboard_control_sensors_present & m.onboard_control_sensors_enabled
        healthy = bits & m.onboard_control_sensors_health
        got += "; healthy: " + ", ".join(
            label for bit, label in ((_GPS_BIT, "GPS"), (_PREARM_BIT, "PREARM")) if healthy & bit
        )
    return CheckResult("streams", not problems, "; ".join(problems) or got)


def check_timestamps(s: Session) -> CheckResult:
    bad = []
    for kind in ("GLOBAL_POSITION_INT", "LOCAL_POSITION_NED", "ATTITUDE", "SYSTEM_TIME"):
        stamps = [m.time_boot_ms for _, m in s.seen.get(kind, [])]
        if any(b < a for a, b in itertools.pairwise(stamps)):
            bad.append(kind)
    n = sum(len(s.seen.get(k, [])) for k in ("GLOBAL_POSITION_INT", "LOCAL_POSITION_NED"))
    if n < 2:
        return CheckResult("timestamps_monotonic", False, "too few timestamped messages")
    return CheckResult(
        "timestamps_monotonic", not bad, f"time_boot_ms goes back in {bad}" if bad else f"{n} ok"
    )


def _ack_check(name: str, s: Session, command: int, *params: float, want: set[int]) -> CheckResult:
    ack = s.command(command, *params)
    if ack is None:
        return CheckResult(name, False, f"no COMMAND_ACK for command {command}")
    ok = ack.result in want
    target_ok = ack.target_system in (0, s.conn.mav.srcSystem)
    detail = f"result {ack.result}" + ("" if target_ok else f", ack to system {ack.target_system}")
    return CheckResult(name, ok and target_ok, detail)


def _mode_params(hb: Any, custom_mode: int) -> tuple[float, float, float]:
    if hb.autopilot == PX4:
        main, sub = (custom_mode >> 16) & 0xFF, (custom_mode >> 24) & 0xFF
        return float(ml.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED), float(main), float(sub)
    return float(ml.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED), float(custom_mode), 0.0


def _switch(s: Session, custom_mode: int) -> tuple[int | None, bool]:
    """DO_SET_MODE to ``custom_mode``: (ack result, whether a heartbeat then showed it)."""
    hb = s.heartbeat
    ack = s.command(ml.MAV_CMD_DO_SET_MODE, *_mode_params(hb, custom_mode))
    if ack is None:
        return None, False
    seen = s.recv(
        {"HEARTBEAT"},
        s.timeout,
        lambda m: m.get_srcComponent() == 1 and m.custom_mode == custom_mode,
    )
    return int(ack.result), seen is not None


def check_mode_switch(s: Session) -> CheckResult:
    """A real switch to another mode that is safe disarmed on the ground, and back."""
    home = s.heartbeat.custom_mode
    safe = _PX4_SAFE_MODES if s.heartbeat.autopilot == PX4 else _ARDUPILOT_SAFE_MODES
    tried = []
    for mode in (m for m in safe if m != home):
        result, shown = _switch(s, mode)
        tried.append(f"{mode:#x}: result {result}")
        if result == 0 and shown:
            back, shown_back = _switch(s, home)
            ok = back == 0 and shown_back
            detail = f"{home:#x} -> {mode:#x} -> {home:#x}" + (
                "" if ok else f" (back: result {back}, shown {shown_back})"
            )
            return CheckResult("mode_switch", ok, detail)
        if result == 0:
            return CheckResult("mode_switch", False, f"{mode:#x} ACCEPTED but never in a HEARTBEAT")
    return CheckResult("mode_switch", False, "no mode switch accepted: " + "; ".join(tried))


def _takeoff_check(s: Session) -> CheckResult:
    """A takeoff while disarmed: ArduPilot refuses it; PX4 accepts it and only selects TAKEOFF
    (commander), which the check sets back. With ``hostile`` the parameters are NaN."""
    hb = s.heartbeat
    home = hb.custom_mode
    params = [float("nan")] * 7 if s.hostile else [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 10.0]
    ack = s.command(ml.MAV_CMD_NAV_TAKEOFF, *params)
    if ack is None:
        return CheckResult("cmd_takeoff", False, "no COMMAND_ACK for NAV_TAKEOFF")
    if ack.result != 0:
        return CheckResult("cmd_takeoff", True, f"refused while disarmed (result {ack.result})")
    now = s.recv({"HEARTBEAT"}, s.timeout, lambda m: m.get_srcComponent() == 1)
    armed = bool(now is not None and now.base_mode & ml.MAV_MODE_FLAG_SAFETY_ARMED)
    restored = True
    if now is not None and now.custom_mode != home:
        restored = _switch(s, home) == (0, True)
    ok = hb.autopilot == PX4 and not armed and restored
    detail = f"accepted while disarmed, mode {now.custom_mode:#x}" if now else "accepted"
    detail += ", set back" if restored else ", NOT set back"
    if hb.autopilot != PX4:
        detail += " (ArduPilot refuses a takeoff while disarmed)"
    return CheckResult("cmd_takeoff", ok, detail)


def check_commands(s: Session) -> list[CheckResult]:
    return [
        _ack_check("cmd_arm_disarm", s, ml.MAV_CMD_COMPONENT_ARM_DISARM, 0, want={0}),
        _takeoff_check(s),
        _ack_check("cmd_unknown", s, _UNKNOWN_COMMAND, want={ml.MAV_RESULT_UNSUPPORTED}),
    ]


def _request(s: Session, name: str, msg_id: int, kind: str) -> CheckResult:
    ack = s.command(ml.MAV_CMD_REQUEST_MESSAGE, msg_id)
    if ack is None or ack.result != 0:
        return CheckResult(name, False, f"REQUEST_MESSAGE {msg_id}: ack {ack and ack.result}")
    since = time.monotonic() - 1.0
    got = any(t >= since for t, _ in s.seen.get(kind, [])) or s.recv({kind}, s.timeout) is not None
    return CheckResult(name, got, f"{kind} {'received' if got else 'not received'}")


def check_requests(s: Session) -> list[CheckResult]:
    return [
        _request(s, "home_position", ml.MAVLINK_MSG_ID_HOME_POSITION, "HOME_POSITION"),
        _request(s, "autopilot_version", ml.MAVLINK_MSG_ID_AUTOPILOT_VERSION, "AUTOPILOT_VERSION"),
    ]


_PARAM_REREAD_ROUNDS = 3
"""Rounds of PARAM_REQUEST_READ by index for values the list stream dropped, as a GCS does."""


def _param_list(s: Session) -> tuple[dict[int, Any], int | None, int]:
    """Every PARAM_VALUE by index, the count the vehicle reports, and how many were re-read.

    The list is streamed once; indices it dropped (a lossy UDP link under load: stock PX4 SITL
    lost 76 of 901 once) are asked for one by one, in a few rounds, as QGroundControl and
    MAVProxy do.
    """
    assert s.sysid is not None
    s.mav.param_request_list_send(s.sysid, s.compid)
    values: dict[int, Any] = {}
    total = None
    deadline = time.monotonic() + 60.0
    while time.monotonic() < deadline and (total is None or len(values) < total):
        # Wait up to the time-out for the first value and between values, as GCSs do.
        m = s.recv({"PARAM_VALUE"}, s.timeout)
        if m is None:
            break
        total = m.param_count
        if m.param_index < total:  # PX4 announces changes made on board with index 65535
            values[m.param_index] = m
    # PX4's count can change while it streams (parameters become used): the last one holds.
    values = {i: m for i, m in values.items() if total is not None and i < total}
    reread = 0
    for _ in range(_PARAM_REREAD_ROUNDS):
        missing = [i for i in range(total or 0) if i not in values]
        if not missing:
            break
        reread += len(missing)
        for index in missing:
            s.mav.param_request_read_send(s.sysid, s.compid, b"", index)
            m = s.recv({"PARAM_VALUE"}, s.timeout, lambda m, i=index: m.param_index == i)
            if m is not None:
                values[index] = m
    return values, total, reread


def check_params(s: Session) -> list[CheckResult]:
    assert s.sysid is not None
    values, total, reread = _param_list(s)
    if not values:
        return [CheckResult("params_list", False, "no PARAM_VALUE after PARAM_REQUEST_LIST")]
    complete = total is not None and len(values) == total
    detail = f"{len(values)} of {total}" + (f" ({reread} re-read by index)" if reread else "")
    out = [CheckResult("params_list", complete, detail)]
    first = values[min(values)]
    s.mav.param_request_read_send(s.sysid, s.compid, first.param_id.encode(), -1)
    got = s.recv({"PARAM_VALUE"}, s.timeout, lambda m: m.param_id == first.param_id)
    out.append(CheckResult("params_read", got is not None, f"{first.param_id}"))
    real = [m for m in values.values() if m.param_type == ml.MAV_PARAM_TYPE_REAL32]
    if not real:
        out.append(CheckResult("params_set", False, "no REAL32 parameter to set"))
        return out
    p = real[0]
    s.mav.param_set_send(s.sysid, s.compid, p.param_id.encode(), p.param_value, p.param_type)
    echo = s.recv({"PARAM_VALUE"}, s.timeout, lambda m: m.param_id == p.param_id)
    ok = echo is not None and struct.pack("<f", echo.param_value) == struct.pack(
        "<f", p.param_value
    )
    out.append(CheckResult("params_set", ok, f"{p.param_id} = {p.param_value} echoed"))
    return out


def check_mission_count(s: Session) -> CheckResult:
    assert s.sysid is not None
    s.mav.mission_request_list_send(s.sysid, s.compid)
    m = s.recv({"MISSION_COUNT"}, s.timeout)
    if m is None:
        return CheckResult("mission_count", False, "no MISSION_COUNT")
    return CheckResult("mission_count", True, f"count {m.count}")


_FENCE = ml.MAV_MISSION_TYPE_FENCE
_FENCE_HALF_SIDE = 100_000
"""1e-7 degrees: the check's fence is a square about 2.2 km across around the vehicle."""


def _fence_download(s: Session) -> list[Any] | None:
    """Every fence item the vehicle stores (MISSION_ITEM_INT), None where it did not answer."""
    assert s.sysid is not None
    s.mav.mission_request_list_send(s.sysid, s.compid, _FENCE)
    count = s.recv({"MISSION_COUNT"}, s.timeout, lambda m: m.mission_type == _FENCE)
    if count is None:
        return None
    items = []
    for seq in range(count.count):
        s.mav.mission_request_int_send(s.sysid, s.compid, seq, _FENCE)
        item = s.recv(
            {"MISSION_ITEM_INT"},
            s.timeout,
            lambda m, seq=seq: m.mission_type == _FENCE and m.seq == seq,
        )
        if item is None:
            return None
        items.append(item)
    s.mav.mission_ack_send(s.sysid, s.compid, ml.MAV_MISSION_ACCEPTED, _FENCE)
    return items


def _fence_upload(s: Session, items: list[tuple[Any, ...]]) -> str:
    """Upload fence items (MISSION_ITEM_INT fields after seq); '' when accepted, else why not."""
    assert s.sysid is not None
    if not items:
        s.mav.mission_clear_all_send(s.sysid, s.compid, _FENCE)
    else:
        s.mav.mission_count_send(s.sysid, s.compid, len(items), _FENCE)
    while True:
        m = s.recv(
            {"MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK"},
            s.timeout,
            lambda m: m.mission_type == _FENCE,
        )
        if m is None:
            return "no answer"
        if m.get_type() == "MISSION_ACK":
            name = ml.enums["MAV_MISSION_RESULT"][m.type].name
            return "" if m.type == ml.MAV_MISSION_ACCEPTED else name
        if not 0 <= m.seq < len(items):
            return f"asked for item {m.seq} of {len(items)}"
        s.mav.mission_item_int_send(s.sysid, s.compid, m.seq, *items[m.seq], _FENCE)


def _fields(item: Any) -> tuple[Any, ...]:
    return (item.frame, item.command, 0, item.autocontinue, item.param1, item.param2,
            item.param3, item.param4, item.x, item.y, item.z)  # fmt: skip


def check_fence(s: Session) -> CheckResult:
    """A fence (an inclusion square around the vehicle, mission_type FENCE) is taken, read back
    equal, and the vehicle's own fence (none, or what it held) put back."""
    where = next(
        (
            m
            for kind in ("HOME_POSITION", "GLOBAL_POSITION_INT")
            for _, m in reversed(s.seen.get(kind, []))
        ),
        None,
    )
    if where is None:
        return CheckResult("fence", False, "no HOME_POSITION or GLOBAL_POSITION_INT to centre on")
    home = where.get_type() == "HOME_POSITION"
    lat, lon = (where.latitude, where.longitude) if home else (where.lat, where.lon)
    before = _fence_download(s)
    if before is None:
        return CheckResult("fence", False, "no fence download (MISSION_REQUEST_LIST, FENCE)")
    d = _FENCE_HALF_SIDE
    square = [(lat - d, lon - d), (lat + d, lon - d), (lat + d, lon + d), (lat - d, lon + d)]
    vertex = ml.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
    items = [
        (ml.MAV_FRAME_GLOBAL, vertex, 0, 1, 4.0, 0.0, 0.0, 0.0, la, lo, 0.0) for la, lo in square
    ]
    refused = _fence_upload(s, items)
    back = _fence_download(s) if not refused else None
    restored = _fence_upload(s, [_fields(m) for m in before])
    if refused:
        return CheckResult("fence", False, f"upload of 4 vertices: {refused}")
    got = [(m.command, m.x, m.y) for m in back or []]
    if got != [(vertex, la, lo) for la, lo in square]:
        return CheckResult("fence", False, f"read back {got}, sent {square}")
    if restored:
        return CheckResult("fence", False, f"4 vertices read back equal; restore: {restored}")
    return CheckResult("fence", True, f"4 vertices read back equal; {len(before)} put back")


@contextlib.contextmanager
def _streamed(s: Session, kinds: tuple[str, ...], interval_us: float) -> Iterator[None]:
    """The streams ``kinds`` at ``interval_us`` for the block, then set back: to their default
    if they were streaming just before (seen within 1.5 s), off if not."""
    recent = time.monotonic()
    s.collect(1.5)  # what streams now, at 1 Hz or more
    before = {k for k in kinds if any(t >= recent for t, _ in s.seen.get(k, []))}
    for kind in kinds:
        _set_interval(s, getattr(ml, f"MAVLINK_MSG_ID_{kind}"), interval_us)
    try:
        yield
    finally:
        for kind in kinds:
            _set_interval(s, getattr(ml, f"MAVLINK_MSG_ID_{kind}"), 0 if kind in before else -1)


def _requested(s: Session, msg_id: int, kind: str) -> Any:
    """The message REQUEST_MESSAGE asked for: it may come before the COMMAND_ACK (read while
    waiting for it), or after; None when it did not come."""
    since = time.monotonic()
    ack = s.command(ml.MAV_CMD_REQUEST_MESSAGE, msg_id)
    if ack is None or ack.result != 0:
        return None
    early = [m for t, m in s.seen.get(kind, []) if t >= since]
    return early[-1] if early else s.recv({kind}, s.timeout)


_PLAN_CAPABILITIES = (
    ml.MAV_PROTOCOL_CAPABILITY_MISSION_INT
    | ml.MAV_PROTOCOL_CAPABILITY_MISSION_FENCE
    | ml.MAV_PROTOCOL_CAPABILITY_MISSION_RALLY
)


def check_plan_capabilities(s: Session) -> CheckResult:
    """AUTOPILOT_VERSION says the mission protocol takes INT items, fences and rally points:
    without these bits MAVSDK refuses missions and geofences before sending anything."""
    m = _requested(s, ml.MAVLINK_MSG_ID_AUTOPILOT_VERSION, "AUTOPILOT_VERSION")
    if m is None:
        return CheckResult("plan_capabilities", False, "no AUTOPILOT_VERSION")
    missing = [
        e.name.removeprefix("MAV_PROTOCOL_CAPABILITY_")
        for bit, e in ml.enums["MAV_PROTOCOL_CAPABILITY"].items()
        if bit & _PLAN_CAPABILITIES and not m.capabilities & bit
    ]
    detail = f"capabilities {m.capabilities:#x}" + (
        f", lacks {', '.join(missing)}" if missing else ""
    )
    return CheckResult("plan_capabilities", not missing, detail)


def _plan_download(s: Session, kind: int) -> list[Any] | None:
    """Every item of plan ``kind`` (MISSION_ITEM_INT), None where the vehicle did not answer."""
    assert s.sysid is not None
    s.mav.mission_request_list_send(s.sysid, s.compid, kind)
    count = s.recv({"MISSION_COUNT"}, s.timeout, lambda m: m.mission_type == kind)
    if count is None:
        return None
    items = []
    for seq in range(count.count):
        s.mav.mission_request_int_send(s.sysid, s.compid, seq, kind)
        item = s.recv(
            {"MISSION_ITEM_INT"},
            s.timeout,
            lambda m, seq=seq: m.mission_type == kind and m.seq == seq,
        )
        if item is None:
            return None
        items.append(item)
    s.mav.mission_ack_send(s.sysid, s.compid, ml.MAV_MISSION_ACCEPTED, kind)
    return items


def _plan_upload(s: Session, kind: int, items: list[tuple[Any, ...]]) -> str:
    """Upload items (MISSION_ITEM_INT fields after seq) of plan ``kind``; '' when accepted,
    else why not. An empty list clears the plan."""
    assert s.sysid is not None
    if not items:
        s.mav.mission_clear_all_send(s.sysid, s.compid, kind)
    else:
        s.mav.mission_count_send(s.sysid, s.compid, len(items), kind)
    while True:
        m = s.recv(
            {"MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK"},
            s.timeout,
            lambda m: m.mission_type == kind,
        )
        if m is None:
            return "no answer"
        if m.get_type() == "MISSION_ACK":
            name = ml.enums["MAV_MISSION_RESULT"][m.type].name
            return "" if m.type == ml.MAV_MISSION_ACCEPTED else name
        if not 0 <= m.seq < len(items):
            return f"asked for item {m.seq} of {len(items)}"
        s.mav.mission_item_int_send(s.sysid, s.compid, m.seq, *items[m.seq], kind)


def _home(s: Session) -> Any:
    return next((m for _, m in reversed(s.seen.get("HOME_POSITION", []))), None)


def check_mission(s: Session) -> CheckResult:
    """A three-item mission (a waypoint at home, a takeoff, a waypoint 50 m north, frame
    GLOBAL_RELATIVE_ALT) is taken and read back with the same commands and positions (item 0
    aside: ArduPilot keeps home there), MISSION_CURRENT reports it, and the vehicle's own
    mission is put back."""
    home = _home(s)
    if home is None:
        return CheckResult("mission", False, "no HOME_POSITION to plan around")
    mission = ml.MAV_MISSION_TYPE_MISSION
    before = _plan_download(s, mission)
    if before is None:
        return CheckResult("mission", False, "no mission download (MISSION_REQUEST_LIST)")
    lat, lon = home.latitude, home.longitude
    north = lat + 4_500  # about 50 m
    rel = ml.MAV_FRAME_GLOBAL_RELATIVE_ALT
    items = [
        (ml.MAV_FRAME_GLOBAL, ml.MAV_CMD_NAV_WAYPOINT, 0, 1, 0, 0, 0, 0, lat, lon, 0.0),
        (rel, ml.MAV_CMD_NAV_TAKEOFF, 0, 1, 0, 0, 0, 0, lat, lon, 10.0),
        (rel, ml.MAV_CMD_NAV_WAYPOINT, 0, 1, 0, 0, 0, 0, north, lon, 10.0),
    ]
    refused = _plan_upload(s, mission, items)
    back = _plan_download(s, mission) if not refused else None
    with _streamed(s, ("MISSION_CURRENT",), 500_000):
        current = s.recv({"MISSION_CURRENT"}, s.timeout) if not refused else None
    restored = _plan_upload(s, mission, [_fields(m) for m in before])
    if refused:
        return CheckResult("mission", False, f"upload of 3 items: {refused}")
    got = [(m.command, m.x, m.y) for m in (back or [])[1:]]
    want = [(cmd, x, y) for _, cmd, *_, x, y, _ in items[1:]]
    if got != want:
        return CheckResult("mission", False, f"read back {got}, sent {want}")
    if current is None:
        return CheckResult("mission", False, "3 items read back equal; no MISSION_CURRENT")
    if restored:
        return CheckResult("mission", False, f"3 items read back equal; restore: {restored}")
    return CheckResult(
        "mission", True, f"3 items read back equal, MISSION_CURRENT total {current.total}"
    )


def check_rally(s: Session) -> CheckResult:
    """A rally point is taken and read back; the vehicle's own rally points put back."""
    home = _home(s)
    if home is None:
        return CheckResult("rally", False, "no HOME_POSITION to place it")
    rally = ml.MAV_MISSION_TYPE_RALLY
    before = _plan_download(s, rally)
    if before is None:
        return CheckResult("rally", False, "no rally download (MISSION_REQUEST_LIST, RALLY)")
    point = (ml.MAV_FRAME_GLOBAL_RELATIVE_ALT, ml.MAV_CMD_NAV_RALLY_POINT, 0, 1, 0, 0, 0, 0,
             home.latitude + 4_500, home.longitude, 20.0)  # fmt: skip
    refused = _plan_upload(s, rally, [point])
    back = _plan_download(s, rally) if not refused else None
    restored = _plan_upload(s, rally, [_fields(m) for m in before])
    if refused:
        return CheckResult("rally", False, f"upload of 1 point: {refused}")
    got = [(m.command, m.x, m.y) for m in back or []]
    if got != [point[1:2] + point[8:10]]:
        return CheckResult("rally", False, f"read back {got}")
    if restored:
        return CheckResult("rally", False, f"restore: {restored}")
    return CheckResult("rally", True, f"1 point read back equal; {len(before)} put back")


_FRAME_TOLERANCE = 3.0
"""Metres between LOCAL_POSITION_NED and GLOBAL_POSITION_INT expressed about the local origin."""


def check_local_frame(s: Session) -> CheckResult:
    """LOCAL_POSITION_NED is metres from the local origin GPS_GLOBAL_ORIGIN names (where the
    vehicle booted, on PX4 and ArduPilot): the global position put in that frame is where the
    local position says, and home lies near it (a vehicle is where it booted)."""
    origin = _requested(s, ml.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN, "GPS_GLOBAL_ORIGIN")
    if origin is None:
        return CheckResult("local_frame", False, "no GPS_GLOBAL_ORIGIN on REQUEST_MESSAGE")
    with _streamed(s, ("LOCAL_POSITION_NED", "GLOBAL_POSITION_INT"), 200_000):
        lpn = s.recv({"LOCAL_POSITION_NED"}, s.timeout)
        gpi = s.recv({"GLOBAL_POSITION_INT"}, s.timeout)
    if lpn is None or gpi is None:
        return CheckResult("local_frame", False, "no LOCAL_POSITION_NED or GLOBAL_POSITION_INT")
    n, e, _ = pymap3d.geodetic2ned(
        gpi.lat * 1e-7, gpi.lon * 1e-7, origin.altitude * 1e-3,
        origin.latitude * 1e-7, origin.longitude * 1e-7, origin.altitude * 1e-3,
    )  # fmt: skip
    off = math.hypot(float(n) - lpn.x, float(e) - lpn.y)
    detail = f"local ({lpn.x:.1f}, {lpn.y:.1f}) m, global about the origin ({n:.1f}, {e:.1f}) m"
    return CheckResult("local_frame", off < _FRAME_TOLERANCE, detail)


def check_ftp(s: Session) -> CheckResult:
    assert s.sysid is not None
    path = b"/mdm-conformance-no-such-file"
    payload = bytearray(251)
    payload[0:2] = (4242).to_bytes(2, "little")
    payload[3] = _FTP_OPEN_RO
    payload[4] = len(path)
    payload[12 : 12 + len(path)] = path
    s.mav.file_transfer_protocol_send(0, s.sysid, s.compid, list(payload))
    m = s.recv({"FILE_TRANSFER_PROTOCOL"}, s.timeout)
    if m is None:
        return CheckResult("ftp_nak", False, "no FILE_TRANSFER_PROTOCOL reply")
    reply = bytes(m.payload)
    seq = int.from_bytes(reply[0:2], "little")
    ok = reply[3] == _FTP_NAK and seq == 4243
    return CheckResult("ftp_nak", ok, f"opcode {reply[3]}, seq {seq}")


def check_timesync(s: Session) -> CheckResult:
    stamp = 123456789
    s.mav.timesync_send(0, stamp)
    m = s.recv({"TIMESYNC"}, s.timeout, lambda m: m.ts1 == stamp and m.tc1 != 0)
    return CheckResult("timesync", m is not None, "answered" if m else "no TIMESYNC reply")


CHECKS: tuple[Callable[[Session], CheckResult | list[CheckResult]], ...] = (
    check_heartbeat,
    check_mavlink2,
    check_ids,
    check_mode_encoding,
    check_streams,
    check_timestamps,
    check_commands,
    check_mode_switch,
    check_requests,
    check_params,
    check_mission_count,
    check_plan_capabilities,
    check_mission,
    check_fence,
    check_rally,
    check_local_frame,
    check_ftp,
    check_timesync,
)
"""Run in this order; the first learns the vehicle's system id."""


def run_checks(
    address: str,
    *,
    sysid: int | None = None,
    timeout: float = 5.0,
    source_system: int = 250,
    hostile: bool = False,
) -> list[CheckResult]:
    """Connect to ``address`` (a pymavlink connection string such as ``udpin:0.0.0.0:14540`` or
    ``tcp:127.0.0.1:5760``) and run every check against the vehicle ``sysid`` (the first
    autopilot heard when None). Returns one result per check; nothing raises for a bad vehicle.
    A closed link ends the run with a failed ``link`` result. ``hostile`` sends NaN parameters
    (a takeoff), which can crash an autopilot."""
    session = Session(address, sysid=sysid, source_system=source_system, timeout=timeout)
    session.hostile = hostile
    results: list[CheckResult] = []
    current = "connect"
    try:
        session.send_heartbeat()
        for check in CHECKS:
            current = check.__name__[6:]
            if session.heartbeat is None and check is not check_heartbeat:
                results.append(CheckResult(current, False, "no heartbeat"))
                continue
            session.send_heartbeat()
            try:
                outcome = check(session)
            except LinkClosedError:
                raise
            except Exception as exc:  # a check must report, not crash the run
                log.exception("check %s crashed", check.__name__)
                outcome = CheckResult(current, False, f"error: {exc!r}")
            results.extend(outcome if isinstance(outcome, list) else [outcome])
    except LinkClosedError as exc:
        results.append(CheckResult("link", False, f"during {current}: {exc}"))
    finally:
        with contextlib.suppress(OSError, LinkClosedError):
            session.close()
    return results
