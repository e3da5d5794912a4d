"""`mavlink-conformance` against stock ArduCopter and PX4 SITL (the real flight code): every
check passes, the autopilot is still running afterwards, and the streams it was sending before
are the streams it sends after (the check set back every rate it changed)."""

from __future__ import annotations

import os
import time
from collections.abc import Callable

import pytest

from mavlink_conformance.cli import main as conformance_main
from tests.sitl import SitlInstance

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil

SPEEDUP = {"arducopter": 5.0, "px4": None}
"""ArduCopter runs stably at 5x here (it only has to boot and answer); PX4 SIH at real time."""
READY_S = 90.0
"""Wall seconds for a position estimate: ArduCopter needs 30-40 sim s for GPS and EKF origin."""
_WATCH = (
    "HEARTBEAT",
    "SYS_STATUS",
    "GLOBAL_POSITION_INT",
    "LOCAL_POSITION_NED",
    "EXTENDED_SYS_STATE",
)


def _streams(url: str, sysid: int, seconds: float, *, ready: bool = False) -> set[str]:
    """Which of _WATCH the vehicle sends on ``url`` within ``seconds`` (with ``ready``: first
    wait until it has a local position, asking for it once and then switching it back off)."""
    conn = mavutil.mavlink_connection(url, source_system=251, source_component=190)
    try:
        if ready:
            conn.wait_heartbeat(timeout=30)
            lpn = mavutil.mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED
            deadline = time.monotonic() + READY_S
            got = None
            while got is None and time.monotonic() < deadline:
                conn.mav.command_long_send(sysid, 1, 511, 0, lpn, 500_000, 0, 0, 0, 0, 0)
                got = conn.recv_match(type="LOCAL_POSITION_NED", blocking=True, timeout=2.0)
            assert got is not None, "no local position estimate"
            conn.mav.command_long_send(sysid, 1, 511, 0, lpn, -1, 0, 0, 0, 0, 0)
            time.sleep(1.0)
        seen: set[str] = set()
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            m = conn.recv_match(blocking=True, timeout=0.2)
            if m is not None and m.get_srcSystem() == sysid and m.get_type() in _WATCH:
                seen.add(m.get_type())
        return seen
    finally:
        conn.close()


@pytest.mark.timeout(300)
@pytest.mark.parametrize("autopilot", ["arducopter", "px4"])
def test_conformance_passes_stock_sitl_and_leaves_it_running_as_it_was(
    autopilot: str,
    sitl_start: Callable[..., SitlInstance],
    capsys: pytest.CaptureFixture[str],
) -> None:
    speedup = SPEEDUP[autopilot]
    inst = sitl_start(autopilot, **({"speedup": speedup} if speedup else {}))
    url = inst.companion_url
    before = _streams(url, inst.sysid, 3.0, ready=True)
    code = conformance_main([url, "--sysid", str(inst.sysid), "--timeout", "5"])
    out = capsys.readouterr().out
    print(out)
    assert code == 0, out + inst.log()
    assert "23/23 checks passed" in out
    assert inst.process.poll() is None, inst.log()  # still running
    after = _streams(url, inst.sysid, 3.0)
    assert "HEARTBEAT" in after
    assert after == before, f"streams before {sorted(before)}, after {sorted(after)}"
