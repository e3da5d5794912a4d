"""The signing rules of mavlink_wire against pymavlink's own signer and parser."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("MAVLINK20", "1")
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from mavlink_wire import (
    SigningKeyError,
    SigningState,
    Verdict,
    load_signing_key,
    passphrase_to_secret,
)
from mavlink_wire.signing_state import EPOCH_2015

KEY = passphrase_to_secret("state-test-key")
NOW = EPOCH_2015 + 3.0e8  # a fixed wall clock, Unix seconds


def _pymavlink_signed(stamp: int, key: bytes = KEY) -> bytes:
    mav = mavlink2.MAVLink(None, srcSystem=245, srcComponent=191)
    mav.signing.secret_key = key
    mav.signing.sign_outgoing = True
    mav.signing.timestamp = stamp
    return bytes(mavlink2.MAVLink_command_long_message(1, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0).pack(mav))


def _ticks(seconds: float) -> int:
    return int((seconds - EPOCH_2015) * 100_000)


def test_new_stream_may_lag_one_minute_then_must_increase() -> None:
    state = SigningState(KEY, clock=lambda: NOW)
    assert state.check(_pymavlink_signed(_ticks(NOW - 90))) is Verdict.REPLAY  # stale stream
    assert state.check(_pymavlink_signed(_ticks(NOW - 30))) is Verdict.OK
    assert state.check(_pymavlink_signed(_ticks(NOW - 30))) is Verdict.REPLAY  # same stamp
    assert state.check(_pymavlink_signed(_ticks(NOW - 30) + 1)) is Verdict.OK


def test_a_forged_frame_does_not_move_the_stream_timestamp() -> None:
    state = SigningState(KEY, clock=lambda: NOW)
    forged = _pymavlink_signed(_ticks(NOW + 3600), key=passphrase_to_secret("attacker-key"))
    assert state.check(forged) is Verdict.BAD_SIGNATURE
    assert state.check(_pymavlink_signed(_ticks(NOW))) is Verdict.OK


def test_own_signatures_pass_pymavlinks_check_and_never_go_backwards() -> None:
    clock = [NOW]
    state = SigningState(KEY, link_id=7, clock=lambda: clock[0])
    plain = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    msg = mavlink2.MAVLink_heartbeat_message(2, 12, 0, 0, 0, 3)
    first = state.sign_frame(bytes(msg.pack(plain)), msg.crc_extra)
    clock[0] = NOW - 10  # the wall clock steps back: timestamps still increase
    second = state.sign_frame(bytes(msg.pack(plain)), msg.crc_extra)
    rx = mavlink2.MAVLink(None)
    rx.signing.secret_key = KEY
    for frame in (first, second):
        assert rx.decode(bytearray(frame)).get_signed()
        assert frame[-13] == 7
    assert int.from_bytes(second[-12:-6], "little") == int.from_bytes(first[-12:-6], "little") + 1


def test_key_file_and_environment(tmp_path: Path) -> None:
    key_file = tmp_path / "k"
    key_file.write_text("state-test-key\n")
    assert load_signing_key(key_file, {}) == KEY
    assert load_signing_key(None, {"MDM_MAVLINK_KEY": "state-test-key"}) == KEY
    assert load_signing_key(None, {"MDM_MAVLINK_KEY": ""}) is None
    assert load_signing_key(None, {}) is None
    key_file.write_bytes("schlüssel-key".encode())
    with pytest.raises(SigningKeyError, match=f"signing key file {key_file}: not ASCII"):
        load_signing_key(key_file, {})
