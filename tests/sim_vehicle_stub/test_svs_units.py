"""Pure parts: parameter encodings, persona mode encodings and the registry, frame counters."""

from __future__ import annotations

import math

import numpy as np
import pymap3d
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sim_vehicle_stub.emulator import Emulator
from sim_vehicle_stub.encoder import Encoder
from sim_vehicle_stub.fast_streams import ATT, GPI, LPN
from sim_vehicle_stub.framing import FrameDecoder, LinkStats
from sim_vehicle_stub.geo_frame import GeoFrame
from sim_vehicle_stub.mavlink import dialect as d
from sim_vehicle_stub.params import bytewise_to_float, float_to_bytewise
from sim_vehicle_stub.personas import ProfileFacts, create_persona, persona_names
from sim_vehicle_stub.personas.base import Action
from tests.emulator_harness import make_config

FACTS = ProfileFacts(speed=20.0, tau=0.33, sensor_radii=(2000.0, 400.0), system_id=3)


def test_registry_knows_both_personas_and_names_unknown_ones() -> None:
    assert persona_names() == ["ardupilot", "px4"]
    with pytest.raises(ValueError, match="px4"):
        create_persona("inav")


@pytest.mark.parametrize(
    ("name", "custom"),
    [("OFFBOARD", 0x60000), ("HOLD", 0x3040000), ("RTL", 0x5040000), ("LAND", 0x6040000),
     ("TAKEOFF", 0x2040000)],
)  # fmt: skip
def test_px4_custom_modes_match_px4(name: str, custom: int) -> None:
    px4 = create_persona("px4")
    assert px4.autopilot == 12
    assert px4.mode(name).custom_mode == custom
    main, sub = (custom >> 16) & 0xFF, custom >> 24
    assert px4.mode_from_command(1, main, sub) == px4.mode(name)


@pytest.mark.parametrize(
    ("name", "number"), [("GUIDED", 4), ("LOITER", 5), ("RTL", 6), ("LAND", 9), ("BRAKE", 17)]
)
def test_ardupilot_custom_modes_match_arducopter(name: str, number: int) -> None:
    ap = create_persona("ardupilot")
    assert ap.autopilot == 3
    assert ap.mode(name).custom_mode == number
    assert ap.mode_from_command(1, number, 0) == ap.mode(name)


def test_px4_integers_travel_bytewise_and_ardupilot_as_floats() -> None:
    px4 = create_persona("px4").param_table(FACTS)
    ap = create_persona("ardupilot").param_table(FACTS)
    assert float_to_bytewise(px4.wire_value("MAV_SYS_ID")) == 3
    assert ap.wire_value("SYSID_THISMAV") == 3.0
    # PX4 reads a bytewise INT32, and tolerates a float-cast one when unambiguous.
    assert px4.decode("MDM_SENSOR", bytewise_to_float(1)) == 1.0
    assert px4.decode("MDM_SENSOR", 1.0) == 1.0
    assert px4.decode("MDM_SENSOR", bytewise_to_float(-1)) == -1.0
    assert ap.decode("MDM_SENSOR", 1.0) == 1.0
    with pytest.raises(ValueError, match="MDM_SENSOR"):
        px4.set("MDM_SENSOR", 2.0)  # two sensors: 0 and 1
    with pytest.raises(ValueError, match="COM_OF_LOSS_T"):
        px4.set("COM_OF_LOSS_T", math.nan)


def test_failsafe_parameters_select_the_real_actions() -> None:
    px4 = create_persona("px4")
    table = px4.param_table(FACTS)
    assert px4.setpoint_loss(table) == (1.0, Action.POSITION)  # stock COM_OBL_RC_ACT 0
    assert px4.link_loss(table) == (10.0, Action.NONE)
    table.set("NAV_DLL_ACT", 2)
    assert px4.link_loss(table)[1] is Action.RTL
    assert px4.fence_action(table) is Action.HOLD
    ap = create_persona("ardupilot")
    table = ap.param_table(FACTS)
    assert ap.setpoint_loss(table) == (3.0, Action.HOLD)
    assert ap.fence_action(table) is Action.RTL
    table.set("FS_GCS_ENABLE", 5)
    assert ap.link_loss(table) == (5.0, Action.LAND)
    scaled = ap.param_table(ProfileFacts(20.0, 0.33, (2000.0, 400.0), 1, timeout_scale=10.0))
    assert ap.setpoint_loss(scaled)[0] == 30.0


def _frame(msg: object) -> bytes:
    return bytes(msg.pack(d.MAVLink(None, srcSystem=9, srcComponent=1)))  # type: ignore[attr-defined]


def test_decoder_counts_each_kind_of_bad_input_and_keeps_good_frames() -> None:
    stats = LinkStats()
    dec = FrameDecoder(stats)
    hb = _frame(d.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
    assert [m.get_type() for m in dec.feed(hb + hb)] == ["HEARTBEAT", "HEARTBEAT"]
    assert dec.feed(hb[:-3]) == []
    assert stats.truncated == 1
    bad = bytearray(hb)
    bad[-1] ^= 0xFF
    assert dec.feed(bytes(bad)) == []
    assert stats.bad_crc == 1
    assert [m.get_type() for m in dec.feed(b"junk" + hb)] == ["HEARTBEAT"]
    assert stats.garbage == 1
    assert stats.rejected_datagrams == 3
    assert stats.messages == 3


def test_stream_decoder_joins_frames_split_across_reads() -> None:
    dec = FrameDecoder(LinkStats(), stream=True)
    hb = _frame(d.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
    assert dec.feed(hb[:5]) == []
    assert [m.get_type() for m in dec.feed(hb[5:])] == ["HEARTBEAT"]
    assert dec.stats.dropped == 0


def test_geodetic_conversion_matches_pymap3d_to_the_millimetre() -> None:
    g = GeoFrame(47.397742, 8.545594, 488.0)
    rng = np.random.default_rng(3)
    n, e = rng.uniform(-1000, 21000, 50), rng.uniform(-1000, 21000, 50)
    up = rng.uniform(0, 120, 50)
    lat, lon, alt = g.to_geodetic(n, e, up)
    ref = pymap3d.ned2geodetic(n, e, -up, g.lat, g.lon, g.alt)
    assert np.max(np.abs(lat - ref[0])) * 111_000 < 1e-3
    assert np.max(np.abs(lon - ref[1])) * 111_000 < 1e-3
    assert np.max(np.abs(alt - ref[2])) < 1e-3
    back = [g.to_local(a, b, c) for a, b, c in zip(lat, lon, alt, strict=True)]
    assert np.allclose(back, np.stack([n, e, up], axis=1), atol=1e-3)


def test_numpy_packed_streams_are_byte_identical_to_pymavlink() -> None:
    emu = Emulator(make_config(5, 29990, speedup=None))
    rng = np.random.default_rng(1)
    emu.fleet.vel[:] = rng.normal(0, 10, (5, 2))
    emu.fleet.alt[:] = 12.3
    emu.fleet.vz[:] = -0.7
    emu.fleet.yaw[:] = [-3.0, -1.0, 0.0, 2.0, 3.1]
    emu.clock.advance(12.345)
    batch = emu.telemetry.position_batch()
    tel = emu.telemetry
    builders = {GPI: tel.global_position_int, LPN: tel.local_position_ned, ATT: tel.attitude}
    for msg_id, build in builders.items():
        for v in emu.vehicles:
            fast = Encoder(v.sysid).frame(msg_id, batch[msg_id][v.index])
            assert fast == Encoder(v.sysid).pack(build(v))
            assert fast == build(v).pack(d.MAVLink(None, srcSystem=v.sysid, srcComponent=1))


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=600), st.booleans())
def test_decoder_never_raises_and_accounts_for_every_read(data: bytes, stream: bool) -> None:
    stats = LinkStats()
    msgs = FrameDecoder(stats, stream=stream).feed(data)
    assert stats.datagrams == 1
    assert stats.messages == len(msgs)
    assert stats.rejected_datagrams in (0, 1)
    if stats.rejected_datagrams == 0 and not stream:
        # Nothing dropped: the bytes were whole frames (or nothing at all).
        assert (len(msgs) > 0) == (len(data) > 0)
