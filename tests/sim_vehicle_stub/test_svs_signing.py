"""MAVLink 2 signing in the emulator, over real UDP with real pymavlink clients: a signed client
flies; unsigned, wrongly signed and replayed commands are not acted on and are counted."""

from __future__ import annotations

import json
import logging
import math
from pathlib import Path
from typing import Any

import pytest

from mavlink_wire import passphrase_to_secret
from sim_vehicle_stub.cli import main as sim_vehicle_main
from tests.emulator_harness import Client, free_udp_base, make_config, running_emulator

log = logging.getLogger(__name__)
KEY = passphrase_to_secret("mdm-signing-test")
WRONG_KEY = passphrase_to_secret("not-the-fleet-key")
PX4_OFFBOARD = 0x60000
ARM, TAKEOFF, SET_MODE = 400, 22, 176


def _signed(c: Client, key: bytes) -> Client:
    c.conn.setup_signing(key, sign_outgoing=True, link_id=1)
    return c


def _is_local(m: Any) -> bool:
    return bool(m.get_type() == "LOCAL_POSITION_NED")


def _armed(c: Client) -> bool:
    hb = c.pump(3, lambda m: m.get_type() == "HEARTBEAT")
    assert hb is not None
    return bool(hb.base_mode & 128)


@pytest.mark.timeout(90)
def test_signed_client_arms_takes_off_and_flies_offboard_under_signing(tmp_path: Path) -> None:
    base = free_udp_base(1)
    config = make_config(1, base, signing_key=KEY, events=tmp_path / "events.jsonl")
    with running_emulator(config) as emu, _signed(Client(base, 1), KEY) as c:
        hb = c.pump(5, lambda m: m.get_type() == "HEARTBEAT")
        assert hb is not None
        assert hb.get_signed()  # pymavlink with the key verified the vehicle's signature
        c.heartbeat()
        assert c.set_param("MIS_TAKEOFF_ALT", 10.0) == 10.0
        assert c.command(ARM, 1) == 0
        assert c.command(TAKEOFF, *[math.nan] * 7) == 0
        assert c.pump(10, lambda m: _is_local(m) and m.z < -9.7)
        c.stream(lambda: c.velocity(0, 0), 0.3)
        assert c.command(SET_MODE, 1, 6, 0) == 0
        moving = c.stream_until(
            lambda: c.velocity(6.0, 0.0), lambda m: _is_local(m) and m.vx > 5.5, 15
        )
        assert moving is not None
        assert moving.get_signed()
        stats = emu.stats()["vehicles"][0]
        log.info("signed flight counters: %s", stats)
        assert stats["signing_rejected"] == 0


@pytest.mark.timeout(90)
def test_unsigned_and_wrong_key_commands_are_rejected_and_counted(tmp_path: Path) -> None:
    events = tmp_path / "events.jsonl"
    config = make_config(1, 25310, signing_key=KEY, events=events)
    with running_emulator(config) as emu:
        with Client(25310, 1) as plain:
            # Unsigned: telemetry still arrives (pymavlink without a key does not check it) ...
            assert plain.pump(5, lambda m: m.get_type() == "HEARTBEAT") is not None
            plain.heartbeat()
            assert plain.command(ARM, 1) is None  # ... but commands get no answer
            plain.conn.mav.set_mode_send(1, 1, PX4_OFFBOARD)
            plain.stream(lambda: plain.velocity(5.0, 0.0), 0.5)
            assert not _armed(plain)
        unsigned = emu.stats()["vehicles"][0]["unsigned"]
        # 1 heartbeat + 3 ARM tries + 1 SET_MODE + ~10 setpoints, at least
        assert unsigned >= 10
        with _signed(Client(25310, 1), WRONG_KEY) as wrong:
            assert wrong.pump(2, lambda m: m.get_type() == "HEARTBEAT") is None  # bad signature
            wrong.heartbeat()
            for attempt in range(3):
                wrong.conn.mav.command_long_send(1, 1, ARM, attempt, 1, 0, 0, 0, 0, 0, 0)
            wrong.stream(lambda: wrong.velocity(5.0, 0.0), 0.5)
        with _signed(Client(25310, 1), KEY) as signed:
            assert not _armed(signed)
            local = signed.pump(3, _is_local)
            assert local is not None
            assert math.hypot(local.vx, local.vy) < 0.01  # no setpoint moved it
        stats = emu.stats()["vehicles"][0]
        log.info("rejection counters: %s", stats)
        assert stats["unsigned"] == unsigned
        assert stats["bad_signature"] >= 5
        assert stats["signing_rejected"] == stats["unsigned"] + stats["bad_signature"]
    logged = [json.loads(line) for line in events.read_text().splitlines()]
    rejected = [e for e in logged if e["event"] == "signing_rejected"]
    assert {e["count"] for e in rejected} >= {1, 10}
    assert {e["reason"] for e in rejected} <= {"unsigned", "bad_signature"}
    assert not any(e["event"] == "armed" for e in logged)


@pytest.mark.timeout(90)
def test_replayed_signed_command_is_rejected(tmp_path: Path) -> None:
    config = make_config(1, 25320, signing_key=KEY)
    with running_emulator(config) as emu, _signed(Client(25320, 1), KEY) as c:
        assert c.pump(5, lambda m: m.get_type() == "HEARTBEAT") is not None
        c.heartbeat()
        arm = c.conn.mav.command_long_encode(1, 1, ARM, 0, 1, 0, 0, 0, 0, 0, 0)
        c.conn.mav.send(arm)
        captured = bytes(arm.get_msgbuf())
        ack = c.pump(3, lambda m: m.get_type() == "COMMAND_ACK" and m.command == ARM)
        assert ack is not None
        assert ack.result == 0
        assert c.command(ARM, 0) == 0  # disarm, signed
        assert not _armed(c)
        c.conn.write(captured)  # the recorded ARM again, byte for byte
        assert c.pump(2, lambda m: m.get_type() == "COMMAND_ACK" and m.command == ARM) is None
        assert not _armed(c)
        stats = emu.stats()["vehicles"][0]
        assert stats["replayed"] == 1
        assert stats["unsigned"] == stats["bad_signature"] == 0


def test_signing_off_by_default_sends_unsigned_frames() -> None:
    with running_emulator(make_config(1, 25330)) as emu, Client(25330, 1) as c:
        hb = c.pump(5, lambda m: m.get_type() == "HEARTBEAT")
        assert hb is not None
        assert hb.get_msgbuf()[2] & 1 == 0  # incompat flag: not signed
        c.heartbeat()
        assert c.command(ARM, 1) == 0
        assert emu.stats()["vehicles"][0]["signing_rejected"] == 0


@pytest.mark.parametrize(
    ("content", "expected"),
    [(None, "No such file"), ("short", "at least 8"), ("two words here", "whitespace")],
)
def test_sim_vehicle_refuses_a_bad_key_file_naming_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], content: str | None, expected: str
) -> None:
    key = tmp_path / "fleet.key"
    if content is not None:
        key.write_text(content)
    assert sim_vehicle_main(["--signing-key-file", str(key), "--duration", "0"]) == 2
    err = capsys.readouterr().err
    assert str(key) in err
    assert expected in err


def test_sim_vehicle_refuses_a_bad_key_in_the_environment(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("MDM_MAVLINK_KEY", "pass word")
    assert sim_vehicle_main(["--duration", "0"]) == 2
    assert "environment variable MDM_MAVLINK_KEY" in capsys.readouterr().err
