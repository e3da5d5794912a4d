"""The emulator keeps no autopilot log and says so when asked (LOG_REQUEST_LIST: one LOG_ENTRY
of num_logs 0, as ArduPilot and PX4 answer when they hold none), on both personas: a pymavlink
client reads the entry, and the companion's MAVSDK download (MAVSDK's LogFiles plugin) names
the empty list instead of waiting for an answer."""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest
from mavsdk.asyncio import Configuration, Mavsdk

from companion.link.mavsdk_logs import download_newest
from tests.emulator_harness import Client, free_udp_base, make_config, running_emulator
from tests.mavsdk_flights import autopilot

PERSONAS = ["ardupilot", "px4"]


@pytest.mark.parametrize("persona", PERSONAS)
def test_a_log_list_request_is_answered_with_no_logs(persona: str) -> None:
    base = free_udp_base(1)
    with running_emulator(make_config(1, base, personas=(persona,))), Client(base, 1) as gcs:
        assert gcs.pump(10.0, lambda m: m.get_type() == "HEARTBEAT") is not None
        gcs.conn.mav.log_request_list_send(1, 1, 0, 0xFFFF)
        entry = gcs.pump(5.0, lambda m: m.get_type() == "LOG_ENTRY")
    assert entry is not None, "no LOG_ENTRY"
    assert (entry.num_logs, entry.last_log_num, entry.size) == (0, 0, 0)


@pytest.mark.timeout(120)
@pytest.mark.parametrize("persona", PERSONAS)
def test_mavsdk_names_a_vehicle_without_logs(persona: str, tmp_path: Path) -> None:
    base = free_udp_base(1)

    async def download() -> str | None:
        async with Mavsdk(Configuration.create_manual(245, 190, True)) as mavsdk:
            system = await autopilot(mavsdk, f"udpin://127.0.0.1:{base}")
            got = await download_newest(system, tmp_path / "autopilot-0", 60.0)
            assert got.path is None
            return got.note

    with running_emulator(make_config(1, base, personas=(persona,))):
        note = asyncio.run(asyncio.wait_for(download(), 90))
    assert note == "the vehicle holds no log"
