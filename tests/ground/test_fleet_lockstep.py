"""`companion fleet` asks the emulator for lockstep when told to, and always flat out."""

from __future__ import annotations

from pathlib import Path

from companion.cli import build_parser
from mdm_ground.fleet.options import default
from mdm_ground.fleet.runner import FleetOptions, emulator_command


def _lockstep(**kw: object) -> bool:
    options = FleetOptions(profile="paper-fixed", out=Path("runs/x"), **kw)  # type: ignore[arg-type]
    return "--lockstep" in emulator_command(options, 12, 20000)


def test_lockstep_by_default_off_only_when_asked_and_always_flat_out() -> None:
    assert _lockstep(speedup=100.0)
    assert not _lockstep(speedup=100.0, lockstep=False)
    assert _lockstep(speedup=0.0, lockstep=False)


def test_the_command_lines_defaults_are_the_options_defaults() -> None:
    args = build_parser().parse_args(["fleet"])
    for name in (
        "speedup",
        "duration",
        "backend",
        "persona",
        "setpoints",
        "seed",
        "land_wait",
        "lockstep",
    ):
        assert getattr(args, name) == default(name), name


def test_the_fleet_command_runs_in_lockstep_unless_told_not_to() -> None:
    parser = build_parser()
    assert parser.parse_args(["fleet"]).lockstep
    assert not parser.parse_args(["fleet", "--no-lockstep"]).lockstep
