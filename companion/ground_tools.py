"""The ground tools' subcommands of `companion` (`fleet`, `map`, `profile`, `watch`) and the map
`companion run` draws at its end, found through the `mdm_search.ground` entry point: the vehicle
side imports nothing of the ground side, and on a vehicle installed without the `[ground]` extra
each of those commands names the install that brings it."""

from __future__ import annotations

import argparse
import logging
from importlib.metadata import entry_points
from pathlib import Path
from typing import Protocol, cast

from mdm_profiles import MissionProfile
from mdm_provenance import extras

log = logging.getLogger(__name__)

GROUP = "mdm_search.ground"
INSTALL = extras.install_hint("ground")
COMMANDS: dict[str, str] = {
    "fleet": "run the emulator (or SITL, or real vehicles) and a companion per vehicle",
    "map": "write map.geojson and map.png of a run directory",
    "profile": "import or export a profile's site from and to ground-station files",
    "watch": "the live page of a team flown elsewhere",
}
"""The ground subcommands, named here so that `companion --help` lists them without them."""


class GroundTools(Protocol):
    """What the entry point's module offers (:mod:`mdm_ground.companion_commands`)."""

    def add_parsers(self, sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None: ...

    def run(self, args: argparse.Namespace) -> int: ...

    def map_after_run(
        self, log_dir: Path, profile: MissionProfile, vehicles: list[int], stem: str
    ) -> None: ...


def load() -> GroundTools | str:
    """The ground tools, or one line saying why they cannot be had and how to get them: their
    entry point, or a module of the [ground] extra, is missing (mdm_ground imports them only
    where a command uses them, so the entry point alone loads without them)."""
    found = entry_points(group=GROUP, name="tools")
    if not found:
        return f"the ground tools are not installed: {INSTALL}"
    absent = extras.missing_module("ground")
    if absent is not None:
        return f"the ground tools are not installed ({absent} is missing): {INSTALL}"
    try:
        return cast(GroundTools, next(iter(found)).load())
    except ImportError as exc:
        missing = f" ({exc.name} is missing)" if exc.name else ""
        return f"the ground tools are not installed{missing}: {INSTALL}"


def add_parsers(
    sub: argparse._SubParsersAction[argparse.ArgumentParser], tools: GroundTools | str
) -> None:
    """The ground subcommands: their own parsers where the tools load, else stand-ins that take
    any arguments, so that running one says what to install (:func:`refused`)."""
    if not isinstance(tools, str):
        tools.add_parsers(sub)
        return
    for name, help_text in COMMANDS.items():
        # no option prefix: every argument is one of ``rest``'s, none is refused before the
        # refusal that names the install
        p = sub.add_parser(
            name, help=f"{help_text} (needs the [ground] extra)", add_help=False, prefix_chars="\0"
        )
        p.add_argument("rest", nargs="*", help=argparse.SUPPRESS)


def refused(command: str, why: str) -> int:
    """A ground subcommand on a vehicle without the ground tools: one line, exit 2."""
    print(f"companion {command}: {why}", flush=True)
    return 2


def draw_run_map(log_dir: Path, profile: MissionProfile, vehicle: int) -> None:
    """`companion run`'s own map (map-I.geojson / .png) where the ground tools are installed;
    else a log line: the mission's logs are on disk and `companion map` draws it elsewhere."""
    tools = load()
    if isinstance(tools, str):
        log.info("no run map drawn: %s", tools)
        return
    tools.map_after_run(log_dir, profile, [vehicle], f"map-{vehicle}")
