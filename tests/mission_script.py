"""One scripted walk through the mission protocol, run the same way against any ArduPilot or PX4
vehicle (the emulator's persona or the real SITL) on the ground, disarmed: uploads of missions,
fences and rally points (MISSION_ITEM_INT and the legacy float MISSION_ITEM), downloads, partial
lists, refusals (a frame, a command, a count too large), MISSION_CURRENT, the mission commands
and the fence's SYS_STATUS bits. It records the answers only (which message, which result
code), never positions, so the emulator and SITL can be compared answer by answer.
"""

from __future__ import annotations

import math
import os
import time
from typing import Any

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil

ml = mavutil.mavlink
STEP = int(0.00027 * 1e7)
"""About 30 m of latitude, in 1e-7 degrees."""
GEOFENCE = 0x100000
Item = (
    tuple[int, int, float, float, int, int, float]
    | tuple[int, int, float, float, int, int, float, float, float]
)
"""frame, command, param1, param2, dlat, dlon (STEP units from home), z[, param3, param4]
(param3 and param4 are 0 where not given)."""
NAN, INF = math.nan, math.inf
ODD_PARAMS: dict[str, list[Item]] = {
    "RTL as MAVSDK's mission plugin sends it (NaN params)": [
        (2, 20, NAN, NAN, 0, 0, 0.0, NAN, NAN)
    ],
    "waypoint yaw NaN": [(3, 16, 0, 2, 1, 0, 10.0, 0, NAN)],
    "DO_CHANGE_SPEED as MAVSDK sends it (z NaN)": [(2, 178, 1, 5, 0, 0, NAN, -1, 0)],
    "waypoint hold NaN": [(3, 16, NAN, 0, 1, 0, 10.0)],
    "waypoint acceptance infinite": [(3, 16, 0, INF, 1, 0, 10.0)],
    "waypoint altitude NaN": [(3, 16, 0, 0, 1, 0, NAN)],
    "land yaw NaN": [(3, 21, 0, 0, 1, 0, 0.0, 0, NAN)],
}
"""One item each after home: which NaN / infinite fields each autopilot takes in a mission."""


def _mission(rtl_frame: int) -> list[Item]:
    return [
        (0, 16, 0, 0, 0, 0, 0.0),
        (3, 22, 0, 0, 0, 0, 10.0),
        (3, 16, 0, 0, 1, 0, 10.0),
        (3, 16, 2, 0, 1, 1, 12.0),
        (rtl_frame, 20, 0, 0, 0, 0, 0.0),
    ]


FENCE_ITEMS: list[Item] = [
    (0, 5001, 4, 0, -3, -3, 0.0),
    (0, 5001, 4, 0, -3, 3, 0.0),
    (0, 5001, 4, 0, 3, 3, 0.0),
    (0, 5001, 4, 0, 3, -3, 0.0),
]
RALLY_ITEMS: list[Item] = [(3, 5100, 0, 0, 1, 0, 20.0)]


class MissionClient:
    """A pymavlink client of one vehicle's mission protocol."""

    def __init__(self, url: str, sysid: int) -> None:
        self.conn: Any = mavutil.mavlink_connection(url, source_system=247, source_component=190)
        self.sysid = sysid
        self.home: tuple[int, int] = (0, 0)
        self._beat = 0.0

    def close(self) -> None:
        self.conn.close()

    def recv(self, kinds: list[str], seconds: float = 3.0, cond: Any = None) -> Any:
        end = time.monotonic() + seconds
        while (left := end - time.monotonic()) > 0:
            if time.monotonic() - self._beat > 0.5:
                self._beat = time.monotonic()
                self.conn.mav.heartbeat_send(ml.MAV_TYPE_GCS, ml.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            m = self.conn.recv_match(type=kinds, blocking=True, timeout=min(left, 0.1))
            if m is None or m.get_srcSystem() != self.sysid or m.get_srcComponent() != 1:
                continue
            if cond is None or cond(m):
                return m
        return None

    def command(self, cmd: int, *p: float) -> int | None:
        args = [*p, *[0.0] * (7 - len(p))]
        self.conn.mav.command_long_send(self.sysid, 1, cmd, 0, *args)
        ack = self.recv(["COMMAND_ACK"], 3.0, lambda m: m.command == cmd)
        return None if ack is None else int(ack.result)

    def wait_home(self, seconds: float) -> None:
        """HOME_POSITION, asked until it comes (a SITL has none before its GPS fix)."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.conn.mav.command_long_send(
                self.sysid, 1, ml.MAV_CMD_REQUEST_MESSAGE, 0, 242, 0, 0, 0, 0, 0, 0
            )
            home = self.recv(["HOME_POSITION"], 2.0)
            if home is not None and home.latitude != 0:
                self.home = (int(home.latitude), int(home.longitude))
                return
        raise TimeoutError(f"no HOME_POSITION from system {self.sysid} in {seconds:.0f} s")

    # ----- the protocol
    def upload(
        self,
        items: list[Item],
        kind: int = 0,
        *,
        legacy: bool = False,
        count: int | None = None,
        partial: tuple[int, int] | None = None,
    ) -> tuple[list[str], Any]:
        """(the request messages seen, the final MISSION_ACK type or 'none')."""
        mav, target = self.conn.mav, (self.sysid, 1)
        if partial is not None:
            mav.mission_write_partial_list_send(*target, *partial, kind)
        else:
            mav.mission_count_send(*target, len(items) if count is None else count, kind)
        asked: list[str] = []
        for _ in range(len(items) + 4):
            r = self.recv(["MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK"], 3.0)
            if r is None:
                return asked, "none"
            if r.get_type() == "MISSION_ACK":
                return asked, int(r.type)
            asked.append(f"{r.get_type()}:{r.seq}")
            offset = partial[0] if partial is not None else 0
            if not 0 <= r.seq - offset < len(items):
                return asked, "asked past the items"
            frame, cmd, p1, p2, dlat, dlon, z, *rest = items[r.seq - offset]
            p3, p4 = rest or (0.0, 0.0)
            lat, lon = self.home[0] + dlat * STEP, self.home[1] + dlon * STEP
            if (frame, cmd) in ((3, 20), (2, 20), (0, 20)):
                lat = lon = 0
            if legacy:
                mav.mission_item_send(
                    *target,
                    r.seq,
                    frame,
                    cmd,
                    0,
                    1,
                    p1,
                    p2,
                    p3,
                    p4,
                    lat * 1e-7,
                    lon * 1e-7,
                    z,
                    kind,
                )
            else:
                mav.mission_item_int_send(
                    *target, r.seq, frame, cmd, 0, 1, p1, p2, p3, p4, lat, lon, z, kind
                )
        return asked, "too many requests"

    def download(self, kind: int = 0, *, legacy: bool = False) -> list[tuple[str, int]]:
        """(message type, command) of every stored item."""
        mav, target = self.conn.mav, (self.sysid, 1)
        mav.mission_request_list_send(*target, kind)
        count = self.recv(["MISSION_COUNT"], 3.0)
        if count is None:
            return [("no MISSION_COUNT", -1)]
        out: list[tuple[str, int]] = []
        for seq in range(count.count):
            if legacy:
                mav.mission_request_send(*target, seq, kind)
            else:
                mav.mission_request_int_send(*target, seq, kind)
            it = self.recv(["MISSION_ITEM_INT", "MISSION_ITEM"], 3.0, lambda m, s=seq: m.seq == s)
            out.append(("none", -1) if it is None else (it.get_type(), int(it.command)))
        mav.mission_ack_send(*target, 0, kind)
        return out

    def past_end(self) -> str:
        self.conn.mav.mission_request_int_send(self.sysid, 1, 99, 0)
        r = self.recv(["MISSION_ITEM_INT", "MISSION_ACK"], 2.0)
        return "none" if r is None else f"{r.get_type()}:{getattr(r, 'type', '')}"

    def fence_bits(self) -> tuple[bool, bool, bool]:
        """SYS_STATUS geofence (present, enabled, healthy) from a fresh SYS_STATUS."""
        self.recv(["SYS_STATUS"], 1.5)
        s = self.recv(["SYS_STATUS"], 3.0)
        if s is None:
            return (False, False, False)
        return (
            bool(s.onboard_control_sensors_present & GEOFENCE),
            bool(s.onboard_control_sensors_enabled & GEOFENCE),
            bool(s.onboard_control_sensors_health & GEOFENCE),
        )


def walk(c: MissionClient) -> dict[str, Any]:
    """The whole walk; the answers by step name."""
    out: dict[str, Any] = {}
    # ArduCopter streams MISSION_CURRENT only when asked (both take the interval).
    out["SET_MESSAGE_INTERVAL MISSION_CURRENT"] = c.command(
        ml.MAV_CMD_SET_MESSAGE_INTERVAL, ml.MAVLINK_MSG_ID_MISSION_CURRENT, 250_000
    )
    out["SET_MESSAGE_INTERVAL SYS_STATUS"] = c.command(
        ml.MAV_CMD_SET_MESSAGE_INTERVAL, ml.MAVLINK_MSG_ID_SYS_STATUS, 500_000
    )
    out["empty download"] = c.download()
    # The first upload: how the vehicle asks before it saw any item (PX4 remembers the client's
    # last item type, ArduPilot always asks with MISSION_REQUEST).
    out["upload int, RTL in MISSION frame"] = c.upload(_mission(2))
    out["download int"] = c.download()
    out["download legacy"] = c.download(legacy=True)
    out["upload legacy"] = c.upload(_mission(2), legacy=True)
    out["upload int, RTL in a global frame"] = c.upload(_mission(3))
    out["upload int again"] = c.upload(_mission(2))
    current = c.recv(["MISSION_CURRENT"], 3.0)
    out["mission current total"] = None if current is None else current.total
    out["upload count 0"] = c.upload([], count=0)
    out["download after count 0"] = c.download()
    out["upload frame 12"] = c.upload([(0, 16, 0, 0, 0, 0, 0.0), (12, 16, 0, 0, 0, 0, 10.0)])
    out["upload command 31999"] = c.upload([(0, 16, 0, 0, 0, 0, 0.0), (3, 31999, 0, 0, 0, 0, 10.0)])
    for name, items in ODD_PARAMS.items():
        out[f"upload {name}"] = c.upload([(0, 16, 0, 0, 0, 0, 0.0), *items])
    c.upload(_mission(2))
    out["partial 1..2"] = c.upload(_mission(2)[1:3], partial=(1, 2))
    out["download after partial"] = c.download()
    out["request past end"] = c.past_end()
    out["DO_SET_MISSION_CURRENT 2"] = c.command(ml.MAV_CMD_DO_SET_MISSION_CURRENT, 2)
    mc = c.recv(["MISSION_CURRENT"], 3.0, lambda m: m.seq == 2)
    out["mission current after set 2"] = None if mc is None else mc.seq
    out["DO_SET_MISSION_CURRENT 99"] = c.command(ml.MAV_CMD_DO_SET_MISSION_CURRENT, 99)
    out["fence bits at boot"] = c.fence_bits()
    out["upload fence"] = c.upload(FENCE_ITEMS, 1)
    out["download fence"] = c.download(1)
    out["upload fence legacy"] = c.upload(FENCE_ITEMS, 1, legacy=True)
    out["upload fence with a waypoint"] = c.upload([(3, 16, 0, 0, 0, 0, 10.0)], 1)
    out["upload rally"] = c.upload(RALLY_ITEMS, 2)
    out["download rally"] = c.download(2)
    out["DO_FENCE_ENABLE 1"] = c.command(ml.MAV_CMD_DO_FENCE_ENABLE, 1)
    out["fence bits enabled"] = c.fence_bits()
    out["DO_FENCE_ENABLE 0"] = c.command(ml.MAV_CMD_DO_FENCE_ENABLE, 0)
    out["fence bits disabled"] = c.fence_bits()
    out["CONDITION_YAW"] = c.command(ml.MAV_CMD_CONDITION_YAW, 90, 10, 1, 0)
    out["DO_SET_HOME current"] = c.command(ml.MAV_CMD_DO_SET_HOME, 1)
    out["NAV_LOITER_TIME"] = c.command(ml.MAV_CMD_NAV_LOITER_TIME, 5)
    out["DO_JUMP"] = c.command(ml.MAV_CMD_DO_JUMP, 1, 2)
    out["NAV_WAYPOINT"] = c.command(ml.MAV_CMD_NAV_WAYPOINT)
    out["clear all"] = _clear(c)
    out["download after clear"] = c.download()
    # Last: PX4 takes the count and waits for items (its upload then blocks other transfers).
    out["upload count 60000"] = c.upload(_mission(2), count=60000)
    return out


def _clear(c: MissionClient) -> Any:
    c.conn.mav.mission_clear_all_send(c.sysid, 1, ml.MAV_MISSION_TYPE_ALL)
    ack = c.recv(["MISSION_ACK"], 3.0)
    return None if ack is None else int(ack.type)
