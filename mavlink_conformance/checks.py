"""The checks, one function each, and :func:`run_checks` that runs them against an address.

Every check is safe on a disarmed vehicle on the ground: commands that could move it are sent
only in forms the autopilot must refuse or that change nothing (set the current mode, disarm).
"""

from __future__ import annotations

import itertools
import logging
import struct
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from mavlink_conformance.session import Session, mavutil

log = logging.getLogger(__name__)
ml = mavutil.mavlink

PX4, ARDUPILOT = ml.MAV_AUTOPILOT_PX4, ml.MAV_AUTOPILOT_ARDUPILOTMEGA
_GPS_BIT, _PREARM_BIT = 0x20, 0x10000000
_STREAMS = ("GLOBAL_POSITION_INT", "LOCAL_POSITION_NED", "SYS_STATUS", "EXTENDED_SYS_STATE")
_UNKNOWN_COMMAND = 31999
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


def check_heartbeat(s: Session) -> CheckResult:
    hb = s.recv({"HEARTBEAT"}, s.timeout, lambda m: m.get_srcComponent() == 1)
    if hb is None:
        return CheckResult("heartbeat", False, f"no autopilot HEARTBEAT in {s.timeout:.0f} s")
    start = time.monotonic()
    count = 0
    while time.monotonic() - start < 2.5:
        if s.recv({"HEARTBEAT"}, 2.5, lambda m: m.get_srcComponent() == 1) is not None:
            count += 1
    rate = count / 2.5
    problems = []
    if hb.type == ml.MAV_TYPE_GCS:
        problems.append("type is GCS")
    if hb.autopilot not in (PX4, ARDUPILOT):
        problems.append(f"autopilot {hb.autopilot} is neither PX4 (12) nor ArduPilot (3)")
    if not hb.base_mode & ml.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
        problems.append("CUSTOM_MODE_ENABLED not set")
    if rate < 0.8:
        problems.append(f"rate {rate:.1f} Hz < 1 Hz")
    detail = f"type {hb.type}, autopilot {hb.autopilot}, {rate:.1f} Hz"
    return CheckResult("heartbeat", not problems, "; ".join(problems) or detail)


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


def check_streams(s: Session) -> CheckResult:
    for kind in _STREAMS:
        msg_id = getattr(ml, f"MAVLINK_MSG_ID_{kind}")
        assert s.sysid is not None
        # Fire and forget: an autopilot that streams by default needs no request.
        s.mav.command_long_send(
            s.sysid, s.compid, ml.MAV_CMD_SET_MESSAGE_INTERVAL, 0, msg_id, 200_000, 0, 0, 0, 0, 0
        )
    s.collect(3.0)
    missing = [k for k in _STREAMS if not s.seen.get(k)]
    problems = [f"missing {', '.join(missing)}"] if missing else []
    status = s.seen.get("SYS_STATUS")
    if status:
        m = status[-1][1]
        bits = m.onboard_control_sensors_present & m.onboard_control_sensors_enabled
        healthy = bits & m.onboard_control_sensors_health
        for bit, label in ((_GPS_BIT, "GPS"), (_PREARM_BIT, "PREARM")):
            if not healthy & bit:
                problems.append(f"SYS_STATUS {label} bit not present/enabled/healthy")
    got = ", ".join(f"{k} x{len(s.seen.get(k, []))}" for k in _STREAMS)
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


_ANY = set(range(0, 10))


def check_commands(s: Session) -> list[CheckResult]:
    hb = s.heartbeat
    out = [
        _ack_check("cmd_set_message_interval", s, ml.MAV_CMD_SET_MESSAGE_INTERVAL,
                   ml.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 100_000, want={0}),
        _ack_check("cmd_arm_disarm", s, ml.MAV_CMD_COMPONENT_ARM_DISARM, 0, want={0}),
        _ack_check("cmd_takeoff", s, ml.MAV_CMD_NAV_TAKEOFF, *([float("nan")] * 6), 0.0,
                   want=_ANY - {0}),
        _ack_check("cmd_unknown", s, _UNKNOWN_COMMAND, want={ml.MAV_RESULT_UNSUPPORTED}),
    ]  # fmt: skip
    if hb is not None:
        # Re-select the current mode: a DO_SET_MODE that changes nothing.
        if hb.autopilot == PX4:
            main, sub = (hb.custom_mode >> 16) & 0xFF, (hb.custom_mode >> 24) & 0xFF
            p = (float(hb.base_mode | 1), float(main), float(sub))
        else:
            p = (float(hb.base_mode | 1), float(hb.custom_mode), 0.0)
        out.append(_ack_check("cmd_do_set_mode", s, ml.MAV_CMD_DO_SET_MODE, *p, want={0}))
    return out


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


def check_params(s: Session) -> list[CheckResult]:
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
        values[m.param_index] = m
    if not values:
        return [CheckResult("params_list", False, "no PARAM_VALUE after PARAM_REQUEST_LIST")]
    complete = total is not None and len(values) == total
    out = [CheckResult("params_list", complete, f"{len(values)} of {total}")]
    first = values[min(values)]
    by_name = s.mav.param_request_read_send(s.sysid, s.compid, first.param_id.encode(), -1)
    del by_name
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
    check_ids,
    check_mode_encoding,
    check_streams,
    check_timestamps,
    check_commands,
    check_requests,
    check_params,
    check_mission_count,
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
) -> list[CheckResult]:
    """Connect to ``address`` (a pymavlink connection string such as ``udpin:0.0.0.0:14540`` or
    ``tcp:127.0.0.1:5760``) and run every check against the vehicle ``sysid`` (the first
    autopilot heard when None). Returns one result per check; nothing raises for a bad vehicle."""
    session = Session(address, sysid=sysid, source_system=source_system, timeout=timeout)
    results: list[CheckResult] = []
    try:
        session.send_heartbeat()
        for check in CHECKS:
            if session.heartbeat is None and check is not check_heartbeat:
                results.append(CheckResult(check.__name__[6:], False, "no heartbeat"))
                continue
            session.send_heartbeat()
            try:
                outcome = check(session)
            except Exception as exc:  # a check must report, not crash the run
                log.exception("check %s crashed", check.__name__)
                outcome = CheckResult(check.__name__[6:], False, f"error: {exc!r}")
            results.extend(outcome if isinstance(outcome, list) else [outcome])
    finally:
        session.close()
    return results
