"""More vehicles than MAVLink system ids: ids repeat every 254 vehicles, each vehicle on its own
UDP port, so a client of one port sees one system; the one shared link (--gcs) is refused."""

from __future__ import annotations

import pytest

from sim_vehicle_stub.config import system_id
from tests.emulator_harness import Client, free_udp_base, make_config, running_emulator


def test_system_ids_repeat_per_block_of_254() -> None:
    assert [system_id(i) for i in (0, 253, 254, 255, 507, 508)] == [1, 254, 1, 2, 254, 1]


@pytest.mark.timeout(90)
def test_vehicle_255_is_system_1_on_its_own_port_and_obeys_there_only() -> None:
    n = 300
    base = free_udp_base(n, gap=n)
    # The vehicles' own ports in the range checked free: 300 ephemeral ones (bind_port_base 0)
    # can land on base + 254 before the client binds it (seen once in CI: errno 98).
    cfg = make_config(n, base, bind_port_base=base + n, speedup=1.0, start_positions=None)
    with running_emulator(cfg) as emu, Client(base + 254, sysid=1) as client:
        client.heartbeat()
        hb = client.pump(5.0, lambda m: m.get_type() == "HEARTBEAT")
        assert hb is not None
        assert hb.get_srcSystem() == 1
        assert emu.vehicles[254].params.get("MAV_SYS_ID") == 1
        # MAV_CMD_COMPONENT_ARM_DISARM to target system 1 on vehicle 254's port: that one only
        assert client.command(400, 1) == 0
        assert [i for i, v in enumerate(emu.vehicles) if v.armed] == [254]


def test_more_than_254_vehicles_on_one_gcs_link_or_beyond_the_port_range_are_refused() -> None:
    with pytest.raises(ValueError, match="--gcs carries every vehicle on one link"):
        make_config(255, 20000, gcs=True)
    with pytest.raises(ValueError, match="base_port 65000 with 600 vehicles needs ports up to"):
        make_config(600, 65000)
    with pytest.raises(ValueError, match="vehicles must be >= 1"):
        make_config(0, 20000)
