"""The emulator keeps a fence uploaded over the mission protocol (mission_type FENCE) and hands
it back, as PX4 and ArduCopter do; missions (mission_type 0) are still refused at once."""

from __future__ import annotations

from typing import Any

import pytest

from tests.emulator_harness import Client, free_udp_base, make_config, running_emulator

FENCE, MISSION = 1, 0
VERTEX = 5001  # MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
ACCEPTED, NO_SPACE, UNSUPPORTED = 0, 4, 3  # MAV_MISSION_RESULT
POLYGON = [(473977000, 85456000), (473987000, 85456000), (473987000, 85476000)]


def _mission(c: Client, kinds: set[str]) -> Any:
    return c.pump(3, lambda m: m.get_type() in kinds)


def _upload(c: Client, items: list[tuple[int, int, int]]) -> Any:
    """Answer the vehicle's item requests until its MISSION_ACK; returns that ack."""
    c.conn.mav.mission_count_send(c.sysid, 1, len(items), FENCE)
    while True:
        msg = _mission(c, {"MISSION_REQUEST_INT", "MISSION_ACK"})
        assert msg is not None, "no answer during the fence upload"
        if msg.get_type() == "MISSION_ACK":
            return msg
        assert msg.mission_type == FENCE
        command, lat, lon = items[msg.seq]
        c.conn.mav.mission_item_int_send(
            c.sysid, 1, msg.seq, 0, command, 0, 1, len(items), 0, 0, 0, lat, lon, 0, FENCE
        )


def _download(c: Client, kind: int = FENCE) -> list[tuple[int, int, int]]:
    c.conn.mav.mission_request_list_send(c.sysid, 1, kind)
    count = _mission(c, {"MISSION_COUNT"})
    assert count is not None
    assert count.mission_type == kind
    out = []
    for seq in range(count.count):
        c.conn.mav.mission_request_int_send(c.sysid, 1, seq, kind)
        item = _mission(c, {"MISSION_ITEM_INT"})
        assert item is not None
        assert item.seq == seq
        out.append((item.command, item.x, item.y))
    return out


@pytest.mark.parametrize("persona", ["px4", "ardupilot"])
def test_a_fence_is_stored_read_back_and_cleared(persona: str) -> None:
    base = free_udp_base(1)
    with running_emulator(make_config(1, base, personas=(persona,))), Client(base, 1) as c:
        assert c.pump(5, lambda m: m.get_type() == "HEARTBEAT") is not None
        assert _download(c) == []
        items = [(VERTEX, lat, lon) for lat, lon in POLYGON]
        ack = _upload(c, items)
        assert (ack.type, ack.mission_type) == (ACCEPTED, FENCE)
        assert _download(c) == items
        assert _download(c, MISSION) == []  # the fence is not a mission
        # A mission still has nowhere to go; a command that is no fence item is refused and
        # leaves the stored fence as it was.
        c.conn.mav.mission_count_send(c.sysid, 1, 3, MISSION)
        ack = _mission(c, {"MISSION_ACK"})
        assert (ack.type, ack.mission_type) == (NO_SPACE, MISSION)
        ack = _upload(c, [(16, *POLYGON[0])])  # MAV_CMD_NAV_WAYPOINT
        assert ack.type == UNSUPPORTED
        assert _download(c) == items
        c.conn.mav.mission_clear_all_send(c.sysid, 1, FENCE)
        ack = _mission(c, {"MISSION_ACK"})
        assert ack.type == ACCEPTED
        assert _download(c) == []
