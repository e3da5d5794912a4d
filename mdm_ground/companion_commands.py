"""The ground tools' subcommands of `companion`, as the vehicle side's entry point
(`mdm_search.ground`) loads them: :func:`add_parsers`, :func:`run` and the after-run map."""

from __future__ import annotations

import argparse

from mdm_ground.fleet.cli_args import add_fleet_parser
from mdm_ground.live_web.cli_args import add_watch_parser
from mdm_ground.run_map.cli_args import add_map_parser, map_after_run, map_command
from mdm_ground.site_files.cli_args import add_profile_parser

__all__ = ["add_parsers", "map_after_run", "run"]


def add_parsers(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Register `fleet`, `map`, `profile` and `watch`."""
    add_fleet_parser(sub)
    add_map_parser(sub)
    add_profile_parser(sub)
    add_watch_parser(sub)


def run(args: argparse.Namespace) -> int:
    """Run the ground subcommand ``args.command`` names; its exit status."""
    if args.command == "map":
        return map_command(args)
    if args.command == "profile":
        from mdm_ground.site_files.commands import profile_command

        return profile_command(args)
    if args.command == "watch":
        from mdm_ground.live_web.commands import watch_command

        return watch_command(args)
    from mdm_ground.fleet.command import fleet_command

    return fleet_command(args)
