"""The `companion run` line the fleet starts for each vehicle (mdm_ground/fleet/runner.py),
parsed by the companion's own parser: what the fleet was asked reaches every companion."""

from __future__ import annotations

import argparse
from pathlib import Path

from companion import cli
from mdm_ground.fleet.cli_args import add_fleet_parser
from mdm_ground.fleet.options import FleetOptions
from mdm_ground.fleet.runner import companion_command
from mdm_ground.fleet.vehicles_file import VehicleEntry


def _run_args(line: list[str]) -> object:
    assert line[1:4] == ["-m", "companion.cli", "run"]
    return cli.build_parser().parse_args(line[3:])


def test_a_real_vehicles_companion_gets_the_fleets_flight_log_wait(tmp_path: Path) -> None:
    entry = VehicleEntry(index=1, link="tcp:127.0.0.1:5770", system_id=2, autopilot="arducopter")
    opts = FleetOptions(profile="paper-fixed", out=tmp_path, flight_log_wait=7.5, land_wait=321.0)
    args = _run_args(companion_command(opts, 1, 0, real=entry))
    assert (args.flight_log_wait, args.land_wait) == (7.5, 321.0)  # type: ignore[attr-defined]
    assert (args.connect, args.system_id) == ("tcp:127.0.0.1:5770", 2)  # type: ignore[attr-defined]


def test_the_fleets_default_flight_log_wait_is_the_companions() -> None:
    sub = argparse.ArgumentParser().add_subparsers(dest="command")
    add_fleet_parser(sub)
    fleet = sub.choices["fleet"].parse_args([])
    run = cli.build_parser().parse_args(["run", "--profile", "paper-fixed", "--vehicle", "0"])
    assert fleet.flight_log_wait == run.flight_log_wait == 300.0
