"""Endpoints and the CLI: TCP per vehicle, the GCS output carrying all vehicles, NACKs for bad
commands, and the real `sim-vehicle` command as a subprocess with its event and stats files."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from sim_vehicle_stub.cli import main as sim_vehicle_main
from tests.emulator_harness import Client, free_udp_base, make_config, mavutil, running_emulator


@pytest.mark.timeout(60)
def test_tcp_server_per_vehicle_carries_its_vehicle_and_takes_commands() -> None:
    cfg = make_config(2, 25000, tcp=True, tcp_base=25060, personas=("ardupilot",))
    with running_emulator(cfg) as emu:
        conn = mavutil.mavlink_connection("tcp:127.0.0.1:25070", source_system=245)
        try:
            hb = conn.recv_match(type="HEARTBEAT", blocking=True, timeout=5)
            assert hb.get_srcSystem() == 2
            assert hb.autopilot == 3
            conn.mav.command_long_send(2, 1, 176, 0, 1, 4, 0, 0, 0, 0, 0)
            ack = conn.recv_match(type="COMMAND_ACK", blocking=True, timeout=5)
            assert ack.result == 0
            assert emu.vehicles[1].mode.name == "GUIDED"
            assert emu.vehicles[0].mode.name == "STABILIZE"
        finally:
            conn.close()


@pytest.mark.timeout(60)
def test_gcs_output_carries_all_vehicles_and_routes_replies_by_target_system() -> None:
    cfg = make_config(3, 25100, gcs=True, gcs_port=25150)
    with running_emulator(cfg) as emu:
        conn = mavutil.mavlink_connection("udpin:127.0.0.1:25150", source_system=245)
        try:
            seen: set[int] = set()
            end = time.monotonic() + 5
            while len(seen) < 3 and time.monotonic() < end:
                m = conn.recv_match(type="HEARTBEAT", blocking=True, timeout=1)
                if m is not None:
                    seen.add(m.get_srcSystem())
            assert seen == {1, 2, 3}
            conn.mav.command_long_send(3, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0)
            ack = conn.recv_match(
                type="COMMAND_ACK",
                blocking=True,
                timeout=5,
                condition="COMMAND_ACK.command==400",
            )
            assert ack.get_srcSystem() == 3
            assert [v.armed for v in emu.vehicles] == [False, False, True]
        finally:
            conn.close()


@pytest.mark.timeout(60)
def test_bad_commands_get_nacks_and_nothing_breaks() -> None:
    with running_emulator(make_config(1, 25200)) as emu, Client(25200, 1) as c:
        assert c.pump(5, lambda m: m.get_type() == "HEARTBEAT") is not None
        assert c.command(31999) == 3  # unknown: UNSUPPORTED
        assert c.command(176, 1, 99, 99) == 2  # no such mode: DENIED
        # Real PX4 takes a takeoff while disarmed: TAKEOFF mode, flown once armed.
        assert c.command(22, *[math.nan] * 7) == 0
        assert emu.vehicles[0].mode.name == "TAKEOFF"
        assert emu.fleet.alt[0] == 0.0
        assert c.command(21) == 2  # land while disarmed
        assert c.command(511, math.inf, math.nan) == 2
        assert c.command(512, 9999) == 2
        assert c.command(400, math.nan, math.inf) == 0  # NaN is not "arm"
        assert not emu.vehicles[0].armed
        # A PARAM_SET out of range is echoed with the unchanged value.
        assert c.set_param("MPC_XY_VEL_MAX", -5.0) == pytest.approx(12.0)  # stock PX4
        # Setpoints in frames the autopilot does not take are ignored, not crashed on.
        c.conn.mav.set_position_target_local_ned_send(0, 1, 1, 42, 0, *[math.nan] * 11)
        c.conn.mav.set_position_target_global_int_send(0, 1, 1, 6, 0, 10**9, 0, 0, *[0] * 8)
        c.conn.mav.set_position_target_local_ned_send(0, 1, 1, 1, 3576, 1e12, 0, -10, *[0] * 8)
        assert c.command(400, 1) == 0
        assert emu.nodes[0].stats.nacks >= 9
        assert emu.vehicles[0].setpoint is None
        assert emu.stats()["tick_errors"] == 0


@pytest.mark.timeout(60)
def test_sim_vehicle_cli_runs_vehicles_and_writes_events_and_stats(tmp_path: Path) -> None:
    events, stats = tmp_path / "events.jsonl", tmp_path / "stats.json"
    exe = Path(sys.executable).parent / "sim-vehicle"
    base = free_udp_base(3, gap=80)  # send to base.., bound on base + 80..
    cmd = [
        str(exe), "--profile", "paper-popup", "-n", "3", "--persona", "px4,ardupilot",
        "--base-port", str(base), "--bind-port-base", str(base + 80), "--speedup", "50",
        "--duration", "250", "--events", str(events), "--stats", str(stats), "--log-level", "WARNING",
    ]  # fmt: skip
    proc = subprocess.Popen(cmd, env={**os.environ, "MAVLINK20": "1"})
    try:
        with Client(base + 1, 2) as c:
            hb = c.pump(10, lambda m: m.get_type() == "HEARTBEAT")
            assert hb is not None
            assert hb.autopilot == 3
            assert c.command(400, 1) == 0
        assert proc.wait(30) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
    report = json.loads(stats.read_text())
    assert report["sim_time"] >= 250.0
    assert report["vehicles"][1]["messages"] >= 1
    log = [json.loads(line) for line in events.read_text().splitlines()]
    appeared = {e["target"]: e["t"] for e in log if e["event"] == "target_appeared"}
    assert appeared[0] == pytest.approx(200.0, abs=0.11)  # T1 pops up at 200 s
    assert 2 not in appeared  # T3 only at 600 s
    assert all(e["t"] <= 250.0 + 0.2 for e in log)
    assert {"event": "armed", "vehicle": 1} in [
        {k: e[k] for k in ("event", "vehicle")} for e in log if "vehicle" in e
    ]


@pytest.mark.parametrize(
    ("persona", "named"),
    [("px4,foo", "unknown persona 'foo'"), (" , ", "no persona given")],
)
def test_sim_vehicle_cli_names_a_bad_persona_without_a_traceback(
    persona: str, named: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as stop:
        sim_vehicle_main(["--persona", persona, "-n", "2"])
    err = capsys.readouterr().err
    assert stop.value.code == 2
    assert f"argument --persona: {named}; known: ardupilot, px4" in err
    assert "Traceback" not in err
