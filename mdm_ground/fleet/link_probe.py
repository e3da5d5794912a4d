"""Before anything arms: every vehicle of a fleet file answers on its link with its system id,
is the autopilot the file says, and stands disarmed on the ground. All links are probed at
once (one thread each); the first refusal, in file order, names the vehicle."""

from __future__ import annotations

import os
import threading
import time
from dataclasses import dataclass

from mdm_ground.fleet.preflight import FleetInputError
from mdm_ground.fleet.vehicles_file import VehicleEntry

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil

_ARMED = 128  # MAV_MODE_FLAG_SAFETY_ARMED
_GCS = 6  # MAV_TYPE_GCS
_AUTOPILOTS = {3: "arducopter", 12: "px4"}  # MAV_AUTOPILOT_ARDUPILOTMEGA, MAV_AUTOPILOT_PX4
_LANDED = {0: "undefined", 1: "on the ground", 2: "in the air", 3: "taking off", 4: "landing"}
_AFTER_HEARTBEAT_S = 1.5
"""Wall seconds spent after the first HEARTBEAT listening for EXTENDED_SYS_STATE (landed state),
which not every autopilot streams unasked."""


@dataclass
class ProbeResult:
    """What one link said (``refusal`` None: fit to fly)."""

    autopilot: str | None = None
    refusal: str | None = None


def _probe(entry: VehicleEntry, timeout: float) -> ProbeResult:
    try:
        conn = mavutil.mavlink_connection(
            entry.link, source_system=245, source_component=191, autoreconnect=False
        )
    except (OSError, ValueError) as exc:
        return ProbeResult(refusal=f"link {entry.link} cannot be opened: {exc}")
    try:
        return _listen(conn, entry, timeout)
    finally:
        conn.close()


def _listen(conn: mavutil.mavfile, entry: VehicleEntry, timeout: float) -> ProbeResult:
    deadline = time.monotonic() + timeout
    heard: set[int] = set()
    beat = None
    landed: int | None = None
    heard_until = deadline
    while time.monotonic() < heard_until:
        try:
            conn.mav.heartbeat_send(_GCS, 8, 0, 0, 0)  # a GCS-like peer: PX4 and ArduPilot answer
            msg = conn.recv_match(
                type=["HEARTBEAT", "EXTENDED_SYS_STATE"], blocking=True, timeout=0.5
            )
        except OSError as exc:
            return ProbeResult(refusal=f"link {entry.link} failed: {exc}")
        if msg is None:
            continue
        src = msg.get_srcSystem()
        heard.add(src)
        if src != entry.system_id:
            continue
        if msg.get_type() == "EXTENDED_SYS_STATE":
            landed = int(msg.landed_state)
        elif msg.type != _GCS and msg.autopilot in _AUTOPILOTS and beat is None:
            beat = msg
            heard_until = min(deadline, time.monotonic() + _AFTER_HEARTBEAT_S)
        if beat is not None and landed is not None:
            break
    if beat is None:
        others = f"heard systems {sorted(heard)}" if heard else "heard nothing"
        return ProbeResult(
            refusal=f"no autopilot HEARTBEAT from system {entry.system_id} on "
            f"{entry.link} within {timeout:g} s ({others})"
        )
    autopilot = _AUTOPILOTS[beat.autopilot]
    if entry.autopilot is not None and entry.autopilot != autopilot:
        return ProbeResult(
            autopilot, f"the file says autopilot {entry.autopilot}, its HEARTBEAT says {autopilot}"
        )
    if beat.base_mode & _ARMED:
        return ProbeResult(autopilot, "already armed: land and disarm it before a fleet start")
    if landed is not None and landed not in (0, 1):
        return ProbeResult(autopilot, f"already flying (landed state: {_LANDED.get(landed)})")
    return ProbeResult(autopilot)


def probe_vehicles(entries: list[VehicleEntry], timeout: float) -> dict[int, str]:
    """Each entry's autopilot by vehicle index; FleetInputError naming the first vehicle (file
    order) that did not answer within ``timeout`` wall seconds, is another autopilot than the
    file says, is armed, or is in the air."""
    results: dict[int, ProbeResult] = {}

    def one(e: VehicleEntry) -> None:
        results[e.index] = _probe(e, timeout)

    threads = [threading.Thread(target=one, args=(e,), name=f"probe-{e.index}") for e in entries]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for e in entries:
        refusal = results[e.index].refusal
        if refusal is not None:
            raise FleetInputError(f"{e.name()}: refused before start: {refusal}")
    return {e.index: str(results[e.index].autopilot) for e in entries}
