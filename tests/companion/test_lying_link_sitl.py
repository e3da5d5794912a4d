"""The lying link (tests/lying_relay.py) once against a stock ArduCopter SITL: the relay takes
the autopilot's TCP link and hands the companion a UDP one with every corruption kind and
transport fault in it. No non-finite or too fast setpoint reaches the autopilot; the search
runs its time; the vehicle comes home, lands and disarms; exit 0."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from companion.telemetry.mission_log import read_records
from tests import sitl
from tests.emulator_harness import free_udp_base
from tests.lying_relay import KINDS, LyingRelay
from tests.profile_files import levels, sensors, write_profile_with
from tests.waiting import wait_until

SPEEDUP = 5.0
SPEED = 10.0
"""The profile's speed: a stock ArduCopter flies about 11 m/s at most (docs/companion.md)."""


@pytest.mark.timeout(900)
def test_arducopter_through_a_lying_link(
    arducopter: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    index = sitl.free_index("arducopter")
    profile = write_profile_with(
        tmp_path / "lying-sitl.yaml",
        "lying-sitl",
        targets=[{"north": 1500.0, "east": 1500.0}],
        fleet={"vehicles": index + 1, "speed": SPEED},
        sensors=sensors(300.0, 100.0),
        policy={"levels": levels(600.0, 300.0, 150.0)},
        mission={"duration": 600.0},
        failsafe={"link_wait": 30.0},
    )
    inst = arducopter(speedup=SPEEDUP, index=index)
    tcp = int(inst.companion_url.rsplit(":", 1)[1])
    port = free_udp_base(1)
    relay = LyingRelay(
        port,
        sysid=inst.sysid,
        vehicle=("127.0.0.1", tcp),
        kinds=KINDS,
        rate_hz=5.0,
        fault_chance=0.05,
        max_speed=SPEED,
    )
    wait_until(relay.connected, 60, "the relay connected to ArduCopter's TCP port")
    log = tmp_path / "companion.log"
    with log.open("ab") as out:
        companion = subprocess.Popen(
            [sys.executable, "-m", "companion.cli", "run", "--profile", str(profile),
             "--vehicle", str(index), "--connect", f"udpin:0.0.0.0:{port}", "--log-dir",
             str(tmp_path), "--duration", "60", "--land-wait", "300", "--flight-log-wait", "0", "--max-speedup",
             str(SPEEDUP), "--no-map"],
            stdout=out, stderr=subprocess.STDOUT, env=dict(os.environ, PYTHONUNBUFFERED="1"),
        )  # fmt: skip
    try:
        rc = companion.wait(timeout=600)
    finally:
        relay.rate_hz = 0.0
        if companion.poll() is None:
            companion.send_signal(signal.SIGKILL)
            companion.wait()
        relay.stop()
    text = log.read_text(errors="replace")
    stats = relay.stats
    assert stats.bad_setpoints == [], stats.bad_setpoints[:5]
    assert stats.setpoints > 100, stats.setpoints
    assert all(stats.injected[k] >= 3 for k in KINDS), stats.injected
    recs = read_records(tmp_path / f"mission-{index}.jsonl")
    assert [r["reason"] for r in recs if r["event"] == "end"] == ["mission time"], text[-3000:]
    exits = [(r["status"], r["cause"]) for r in recs if r["event"] == "exit"]
    assert exits == [(0, "RTL: landed and disarmed")], text[-3000:]
    assert rc == 0
    assert "vehicle clock went back" not in text
    dropped = {r["cause"]: r["total"] for r in recs if r["event"] == "telemetry_dropped"}
    for cause in ("non-finite", "position out of range", "moved too fast", "other component"):
        assert cause in dropped, dropped
    print(
        f"\narducopter SITL: injected {dict(stats.injected)}, faults {dict(stats.faults)}, "
        f"setpoints checked {stats.setpoints}, bad {len(stats.bad_setpoints)}, dropped "
        f"{dropped}, exit {exits}"
    )
