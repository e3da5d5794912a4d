"""MAVLink 2 signing on the companion side: a signed fleet flies; the pymavlink link drops a
vehicle signed with another key; the MAVSDK backend refuses a key; bad keys fail clearly."""

from __future__ import annotations

import asyncio
import json
import subprocess
import sys
from pathlib import Path

import pytest

from companion.link.messages import Heartbeat
from companion.link.pymavlink_link import PymavlinkLink
from mavlink_wire import passphrase_to_secret
from mdm_ground.fleet.runner import FleetOptions, run_fleet
from tests.emulator_harness import make_config, running_emulator

PASSPHRASE = "companion-signing-test"


@pytest.mark.usefixtures("fleet_processes")
@pytest.mark.timeout(300)
def test_signed_fleet_arms_flies_and_no_message_is_rejected(tmp_path: Path) -> None:
    key_file = tmp_path / "fleet.key"
    key_file.write_text(PASSPHRASE + "\n")
    result = run_fleet(
        FleetOptions(
            profile="paper-fixed",
            out=tmp_path,
            vehicles=2,
            speedup=50.0,
            duration=120.0,
            seed=3,
            wall_limit=200,
            signing_key_file=key_file,
        )
    )
    assert len(result.end_reasons) == 2, result.end_reasons
    assert "MAVLink signing on" in (tmp_path / "emulator.log").read_text()
    events = [json.loads(x) for x in (tmp_path / "emulator-events.jsonl").read_text().splitlines()]
    armed = {e["vehicle"] for e in events if e["event"] == "armed"}
    offboard = {e["vehicle"] for e in events if e["event"] == "mode" and e["mode"] == "OFFBOARD"}
    assert armed == offboard == {0, 1}
    assert not [e for e in events if e["event"] == "signing_rejected"]


async def _first_heartbeat(link: PymavlinkLink, seconds: float) -> bool:
    loop = asyncio.get_running_loop()
    end = loop.time() + seconds
    while (left := end - loop.time()) > 0:
        try:
            event = await asyncio.wait_for(link.events.get(), left)
        except TimeoutError:
            return False
        if isinstance(event, Heartbeat):
            return True
    return False


async def _fly_link(port: int, key: bytes) -> tuple[bool, bool, int]:
    link = PymavlinkLink(
        url=f"udpin:127.0.0.1:{port}",
        target_system=1,
        tlog=None,
        signing_key=key,
        command_tries=2,
        command_timeout=0.5,
    )
    async with link:
        heard = await _first_heartbeat(link, 3.0)
        armed = bool(await link.arm())
        return heard, armed, link.signing_rejected


@pytest.mark.timeout(60)
def test_pymavlink_link_arms_with_the_key_and_drops_a_vehicle_signed_otherwise() -> None:
    key = passphrase_to_secret(PASSPHRASE)
    with running_emulator(make_config(1, 25520, signing_key=key)) as emu:
        heard, armed, rejected = asyncio.run(_fly_link(25520, key))
        assert (heard, armed, rejected) == (True, True, 0)
        heard, armed, rejected = asyncio.run(_fly_link(25520, passphrase_to_secret("x" * 12)))
        assert not heard
        assert not armed
        assert rejected > 0  # the vehicle's telemetry, signed with the fleet key
        stats = emu.stats()["vehicles"][0]
        assert stats["signing_rejected"] == 0  # nothing reached it: no reply address learnt
        assert emu.vehicles[0].armed


def test_mavsdk_backend_refuses_a_signing_key(tmp_path: Path) -> None:
    key_file = tmp_path / "fleet.key"
    key_file.write_text(PASSPHRASE)
    run = subprocess.run(
        [sys.executable, "-m", "companion.cli", "run", "--profile", "paper-fixed",
         "--vehicle", "0", "--backend", "mavsdk", "--signing-key-file", str(key_file),
         "--log-dir", str(tmp_path)],
        capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert run.returncode == 2
    assert "mavsdk backend cannot sign" in run.stderr
    with pytest.raises(ValueError, match="mavsdk backend cannot sign"):
        run_fleet(
            FleetOptions(
                profile="paper-fixed", out=tmp_path, backend="mavsdk", signing_key_file=key_file
            )
        )
    assert not (tmp_path / "emulator.log").exists()  # refused before starting anything


def test_companion_run_names_a_missing_key_file(tmp_path: Path) -> None:
    missing = tmp_path / "nowhere.key"
    run = subprocess.run(
        [sys.executable, "-m", "companion.cli", "run", "--profile", "paper-fixed",
         "--vehicle", "0", "--signing-key-file", str(missing), "--log-dir", str(tmp_path)],
        capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert run.returncode == 2
    assert f"signing key file {missing}" in run.stderr
