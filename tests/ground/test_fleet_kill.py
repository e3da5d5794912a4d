"""A `companion fleet` team killed at once (``kill -9`` of the fleet runner and of every
companion, what a crashed ground computer running them all looks like) mid-search: each
vehicle, a mixed team of the emulator's PX4 and ArduCopter personas reached over
``--vehicles-file``, returns by its own safety net (written by its companion before arming)
and lands, disarmed. Judged from the emulated autopilots' own state."""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import pytest
import yaml

from mdm_profiles import load_profile
from sim_vehicle_stub.personas.base import Behaviour
from tests.companion.test_kill_failsafe import alive, descendants
from tests.emulator_harness import free_udp_base, make_config, running_emulator
from tests.fleet_cli import start_fleet
from tests.waiting import wait_until

PERSONAS = ("px4", "ardupilot", "px4")
INSIDE = ((600.0, 1000.0), (700.0, 1000.0), (800.0, 1000.0))  # inside the site's fence


@pytest.mark.timeout(240)
def test_a_team_killed_at_once_leaves_every_vehicle_returning(tmp_path: Path) -> None:
    profile = load_profile("field-duebendorf")
    n = len(PERSONAS)
    base = free_udp_base(n)
    entries = [
        {"index": i, "link": f"udpin:127.0.0.1:{base + i}", "system_id": i + 1} for i in range(n)
    ]
    vehicles_file = tmp_path / "fleet.yaml"
    vehicles_file.write_text(yaml.safe_dump({"vehicles": entries}, sort_keys=False))
    config = make_config(
        n, base, profile=profile, speedup=20.0, personas=PERSONAS, start_positions=INSIDE
    )
    with running_emulator(config) as emu:
        runner = start_fleet(
            "--profile", "field-duebendorf", "--vehicles-file", str(vehicles_file),
            "--out", str(tmp_path / "run"), "--sensor-source", "virtual", "--quiet",
            output=tmp_path / "fleet.out",
        )  # fmt: skip

        def output() -> str:
            return (tmp_path / "fleet.out").read_text(errors="replace")

        def searching() -> bool:
            return all(
                v.armed
                and v.mode.behaviour is Behaviour.EXTERNAL
                and v.fleet.alt[v.index] > profile.fleet.altitude - 2.0
                for v in emu.vehicles
            )

        try:
            wait_until(searching, 150.0, "every vehicle searching", context=output)
            team = [runner.pid, *descendants(runner.pid)]
            for pid in team:  # at once: no companion hears the runner's end
                os.kill(pid, signal.SIGKILL)
            killed = time.monotonic()
            returned: dict[int, float] = {}

            def all_returning() -> bool:
                for v in emu.vehicles:
                    if v.index not in returned and v.mode.behaviour is Behaviour.RTL:
                        returned[v.index] = time.monotonic() - killed
                return len(returned) == n

            wait_until(all_returning, 30.0, "every vehicle in RTL", context=output)
            wait_until(
                lambda: all(v.landed and not v.armed for v in emu.vehicles),
                180.0,
                "every vehicle landed and disarmed",
            )
        finally:
            if runner.poll() is None:
                os.killpg(runner.pid, signal.SIGKILL)
            runner.wait()
    assert alive(team) == [], team
    print(
        "\nfleet killed at once: kill -> RTL per vehicle (wall s at 20x) "
        + ", ".join(f"{i} {PERSONAS[i]} {returned[i]:.1f}" for i in sorted(returned))
        + "; all landed, disarmed"
    )
    assert max(returned.values()) < 10.0, returned
