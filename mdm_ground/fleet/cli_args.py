"""Command-line options of `companion fleet`."""

from __future__ import annotations

import argparse
from pathlib import Path

from companion.link.factory import BACKENDS
from companion.sensors.factory import SENSOR_SOURCES
from companion.telemetry.mqtt.cli_args import add_mqtt_arguments
from mdm_ground.fleet.options import default
from mdm_ground.fleet.sitl_team import SITL_KINDS
from mdm_ground.live_web.cli_args import add_web_arguments


def add_fleet_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Register `companion fleet`."""
    p = sub.add_parser(
        "fleet",
        help="run the emulator and N companions on this machine; print what they found",
    )
    p.add_argument("--profile", default="paper-fixed", help="profile file or built-in name")
    p.add_argument("--vehicles", type=int, help="number of vehicles (default: profile)")
    p.add_argument(
        "--speedup", type=float, default=default("speedup"), help="sim seconds per wall second"
    )
    p.add_argument("--duration", type=float, default=default("duration"), help="search time, sim s")
    p.add_argument("--backend", choices=BACKENDS, default=default("backend"))
    p.add_argument("--persona", choices=("px4", "ardupilot"), default=default("persona"))
    p.add_argument("--setpoints", choices=("velocity", "position"), default=default("setpoints"))
    p.add_argument("--seed", type=int, default=default("seed"))
    p.add_argument(
        "--base-port",
        type=int,
        help="first of 2N UDP ports: companions BASE+i, the emulator BASE+N+i; "
        "refused when busy (default: a free block, printed at start)",
    )
    p.add_argument(
        "--out", type=Path, help="run directory, new or empty (default runs/fleet-<time>)"
    )
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue the run in --out: vehicles that had not ended fly on from "
        "their mission logs (README: what a fleet run leaves on disk)",
    )
    p.add_argument(
        "--land-wait",
        type=float,
        default=default("land_wait"),
        help="after a stop (Ctrl-C), sim s the emulator runs on so the vehicles "
        "can land (default 900)",
    )
    p.add_argument("--json", action="store_true", help="print the results as JSON")
    p.add_argument(
        "--lockstep",
        action=argparse.BooleanOptionalAction,
        default=default("lockstep"),
        help="sim time waits for every companion's setpoint each tick, so setpoints "
        "stay at 10 Hz in vehicle time on a busy host (default); --no-lockstep runs "
        "at the requested speed-up and companions skip stale positions",
    )
    p.add_argument(
        "--sensor-source",
        choices=SENSOR_SOURCES,
        help="every companion's sensor source (default: the profile's sensor_source.kind)",
    )
    p.add_argument("--quiet", action="store_true", help="no live progress lines")
    p.add_argument(
        "--signing-key-file",
        type=Path,
        help="MAVLink 2 signing passphrase file for the emulator and every companion "
        "(default: $MDM_MAVLINK_KEY, inherited; neither: off)",
    )
    p.add_argument(
        "--vehicles-file",
        type=Path,
        help="fly the real (or SITL) vehicles this YAML file lists, no emulator "
        "(docs/companion.md, 'Flying real vehicles')",
    )
    p.add_argument(
        "--sitl",
        choices=SITL_KINDS,
        help="start one SITL instance per vehicle at its start point in the "
        "profile's site, fly them, stop them at the end (mixed: ArduCopter, PX4, ...)",
    )
    p.add_argument(
        "--sitl-speedup",
        type=float,
        default=default("sitl_speedup"),
        help="each SITL instance's speed-up (default 1)",
    )
    p.add_argument(
        "--link-timeout",
        type=float,
        default=default("link_timeout"),
        help="wall s each real vehicle has to answer on its link before the run is "
        "refused (default 30; --sitl: at least 60)",
    )
    p.add_argument(
        "--flight-log-wait",
        type=float,
        default=default("flight_log_wait"),
        help="real vehicles: wall s each companion spends downloading its autopilot's own log "
        "once landed (default 300; 0: none)",
    )
    p.add_argument(
        "--web",
        metavar="[HOST:]PORT",
        help="serve the live page of the run there (with --mqtt over that broker, else over "
        "an embedded one the page runs; docs/live_web.md)",
    )
    add_web_arguments(p)
    p.add_argument(
        "--gcs",
        metavar="udpout:HOST:PORT",
        help="the emulator also sends every vehicle's MAVLink to this ground "
        "station (QGroundControl, MAVProxy)",
    )
    add_mqtt_arguments(p)
