"""The `companion` command: `run` flies one vehicle; the ground tools add `fleet` (the emulator
and N companions), `map`, `profile` and `watch` (:mod:`companion.ground_tools`)."""

from __future__ import annotations

import argparse
import asyncio
import logging
import os
import signal
import sys
from collections.abc import Coroutine
from dataclasses import fields
from pathlib import Path
from typing import Any

from companion import ground_tools
from companion.autopilots import FlightMode
from companion.fly import REFUSED, STOPPED_BY_SECOND_SIGNAL, check_flight, fly
from companion.link.address import parse_address
from companion.link.factory import BACKENDS, Backend, make_link
from companion.link.log_transfer import FLIGHT_LOG_WAIT_S
from companion.link.serial_device import check_serial
from companion.mission import MissionConfig
from companion.mission.battery_reserve import reserve_rule
from companion.mission.mission_exit import MissionExit
from companion.mission.safety_net import SAFETY_NET_REFUSED
from companion.sensors.factory import SENSOR_SOURCES
from companion.service.boot_mission import begin_boot_mission
from companion.service.command import add_service_parser, service_command
from companion.telemetry.log_file import add_log_file
from companion.telemetry.mqtt.cli_args import add_mqtt_arguments, mqtt_spec
from mavlink_wire import ENV_VAR, load_signing_key
from mdm_core.ports import VEHICLE_UDP_BASE
from mdm_profiles import ProfileError, SensorSourceKind, load_profile
from mdm_profiles.ceiling import check_ceiling
from mdm_profiles.mqtt_spec import MqttSpec
from mdm_provenance import add_version_flag

log = logging.getLogger("companion")
LOG_FORMAT = "%(asctime)s %(levelname)s %(name)s: %(message)s"


def _run_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser("run", help="fly one vehicle's MDM search")
    p.add_argument("--profile", required=True, help="profile file or built-in name")
    p.add_argument("--vehicle", type=int, required=True, help="0-based vehicle index")
    p.add_argument(
        "--connect",
        help="link URL: udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT or serial:DEVICE:BAUD "
        "(default udpin:0.0.0.0:BASE_PORT+I)",
    )
    p.add_argument(
        "--system-id",
        type=int,
        help="the vehicle's MAVLink system id, 1-255 (default: --vehicle + 1)",
    )
    p.add_argument("--base-port", type=int, default=VEHICLE_UDP_BASE)
    p.add_argument("--backend", choices=BACKENDS, default="pymavlink")
    p.add_argument("--setpoints", choices=("velocity", "position"), default="velocity")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--log-dir", type=Path, default=Path("runs"))
    p.add_argument("--duration", type=float, help="search time, vehicle s (default: profile)")
    p.add_argument("--end-action", choices=("rtl", "land"), help="default: profile site, else rtl")
    p.add_argument("--land-wait", type=float, default=600.0, help="vehicle s to wait to land")
    p.add_argument(
        "--flight-log-wait",
        type=float,
        default=FLIGHT_LOG_WAIT_S,
        help="wall s to download the autopilot's own log once landed (0: none)",
    )
    p.add_argument(
        "--max-speedup",
        type=float,
        help="vehicle s per wall s the vehicle runs at (a simulator's speed-up): "
        "positions whose clock runs faster are dropped (default: unknown)",
    )
    p.add_argument("--no-tlog", action="store_true", help="do not write the .tlog")
    p.add_argument(
        "--no-map",
        action="store_true",
        help="draw no map-I.geojson / map-I.png at the end (a fleet draws one map of "
        "every vehicle instead)",
    )
    p.add_argument(
        "--sensor-source",
        choices=SENSOR_SOURCES,
        help="where readings come from (default: the profile's sensor_source.kind)",
    )
    p.add_argument(
        "--dedicated-link",
        action="store_true",
        help="the link carries only this companion: switch off streams it does not "
        "read (never with a ground station on the same link)",
    )
    p.add_argument(
        "--signing-key-file",
        type=Path,
        help=f"MAVLink 2 signing passphrase file (default: ${ENV_VAR}; neither: off)",
    )
    p.add_argument(
        "--log-file",
        type=Path,
        help="the log lines in this file too, rotated at 5 MB, 3 kept (the service's unit)",
    )
    p.add_argument(
        "--new-mission-per-boot",
        action="store_true",
        help="keep --log-dir's mission within a boot and when it did not end (its resume rules); "
        "move a mission that ended in an earlier boot to LOG_DIR/ended/ (the service's unit)",
    )
    p.add_argument("-v", "--verbose", action="store_true")
    add_mqtt_arguments(p)


def build_parser(
    tools: ground_tools.GroundTools | str | None = None,
) -> argparse.ArgumentParser:
    """The `companion` command line: `run` and the ground tools' subcommands (``tools``, by
    default whatever :func:`ground_tools.load` finds)."""
    parser = argparse.ArgumentParser(prog="companion", description=__doc__)
    add_version_flag(parser)
    sub = parser.add_subparsers(dest="command", required=True)
    _run_parser(sub)
    add_service_parser(sub)
    ground_tools.add_parsers(sub, ground_tools.load() if tools is None else tools)
    return parser


def _checked_run_options(run_argv: list[str]) -> argparse.Namespace:
    """`companion run`'s options for `companion service`: parsed and checked as `run` would."""
    args = build_parser("").parse_args(["run", *run_argv])
    checked_run(args)
    return args


def main(argv: list[str] | None = None) -> int:
    """Entry point of the `companion` command."""
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["service"]:  # its other options are `companion run`'s, checked by it
        try:
            return service_command(argv[1:], _checked_run_options)
        except ProfileError as exc:
            print(f"companion service: {exc}", file=sys.stderr)
            return 2
        except ValueError as exc:
            print(f"companion service: {exc}", file=sys.stderr)
            return 2
    # `run` parses with its own parser alone: loading the ground tools (the entry point and
    # mdm_ground's parsers) would cost each companion's start-up for nothing
    tools = "" if argv[:1] == ["run"] else ground_tools.load()
    args = build_parser(tools).parse_args(argv)
    logging.basicConfig(
        level=logging.DEBUG if getattr(args, "verbose", False) else logging.INFO,
        format=LOG_FORMAT,
    )
    try:
        if args.command == "run":
            return run_command(args)
        if isinstance(tools, str):
            return ground_tools.refused(args.command, tools)
        return tools.run(args)
    except ProfileError as exc:
        print(f"companion: {exc}", file=sys.stderr)
        return 2
    except ValueError as exc:
        print(f"companion: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


def run_command(args: argparse.Namespace) -> int:
    """`companion run`: one vehicle until its mission ends."""
    config, url, mqtt, sensor_source = checked_run(args)
    if args.new_mission_per_boot:
        begin_boot_mission(config.log_dir, config.vehicle)
    if args.log_file is not None:
        add_log_file(args.log_file, LOG_FORMAT)
    address = parse_address(url)
    if address.is_serial:  # missing, busy, no permission: refused now (exit 2), not retried
        check_serial(address)
    signing_key = load_signing_key(args.signing_key_file)
    fly = _fly(
        config,
        url,
        args.backend,
        tlog=not args.no_tlog,
        mqtt=mqtt,
        signing_key=signing_key,
        sensor_source=sensor_source,
    )
    if args.backend == "mavsdk":
        reason, end = _run_mavsdk(fly)
        _say_end(args.vehicle, reason, end)
        _map(config, reason, args.no_map)
        os._exit(_exit_status(reason, end))  # see _run_mavsdk: never join MAVSDK's blocked threads
    reason, end = asyncio.run(fly)
    _say_end(args.vehicle, reason, end)
    _map(config, reason, args.no_map)
    return _exit_status(reason, end)


def checked_run(
    args: argparse.Namespace,
) -> tuple[MissionConfig, str, MqttSpec | None, SensorSourceKind]:
    """`companion run`'s options checked (raises ValueError naming what is wrong) before any
    socket or file: the mission's configuration, the link URL, MQTT, the sensor source."""
    profile = load_profile(args.profile)
    if not 0 <= args.vehicle < profile.fleet.vehicles:
        raise ValueError(f"--vehicle {args.vehicle}: profile has {profile.fleet.vehicles} vehicles")
    check_ceiling(profile, profile.fleet.vehicles)  # the whole team's layers, before connecting
    if args.system_id is not None and not 1 <= args.system_id <= 255:
        raise ValueError(f"--system-id {args.system_id}: must be 1..255 (a MAVLink system id)")
    site = profile.site
    end_action = args.end_action or (site.end_action if site is not None else "rtl")
    config = MissionConfig(
        vehicle=args.vehicle,
        profile=profile,
        setpoints=args.setpoints,
        seed=args.seed,
        log_dir=args.log_dir,
        duration=args.duration,
        end_action=FlightMode(end_action),
        battery_min=site.battery_min if site is not None else 20.0,
        battery_reserve=reserve_rule(site, profile.fleet.speed, end_action),
        land_wait=args.land_wait,
        flight_log_wait=args.flight_log_wait,
        dedicated_link=args.dedicated_link,
        target_system=args.system_id,
        max_speedup=args.max_speedup,
    )
    port = args.base_port + args.vehicle
    url = args.connect or f"udpin:0.0.0.0:{port}"
    if args.connect is None and site is not None and site.connect:
        url = site.connect.format(port=port)
    mqtt = mqtt_spec(args, profile.mqtt)
    sensor_source: SensorSourceKind = args.sensor_source or profile.sensor_source.kind
    check_flight(config, mqtt, sensor_source)
    parse_address(url)
    return config, url, mqtt, sensor_source


def _say_end(vehicle: int, reason: str, end: MissionExit | None) -> None:
    """The mission's end reason and, in one line, how the vehicle was left."""
    how = "" if end is None else f"; exit {end.status}: {end.cause}"
    print(f"vehicle {vehicle}: mission ended ({reason}){how}", flush=True)


def _map(config: MissionConfig, reason: str, skip: bool) -> None:
    """The run's map, unless asked for none or a second signal asked to exit at once."""
    if not skip and reason != STOPPED_BY_SECOND_SIGNAL:
        ground_tools.draw_run_map(config.log_dir, config.profile, config.vehicle)


def _exit_status(reason: str, end: MissionExit | None) -> int:
    """130 when a second signal cut the mission short; 2 when the vehicle's safety net is not
    as needed (failsafe.safety_net); 1 when the companion refused to start;
    else the mission's own (:class:`MissionExit`): 0 only when the vehicle was seen landed and
    disarmed, or the end action accepted where ``--land-wait 0`` asked not to wait."""
    if reason == STOPPED_BY_SECOND_SIGNAL:
        return 130
    if reason.startswith(SAFETY_NET_REFUSED):
        return 2
    if reason.startswith(REFUSED) or end is None:
        return 1
    return end.status


def _run_mavsdk(
    coro: Coroutine[Any, Any, tuple[str, MissionExit | None]],
) -> tuple[str, MissionExit | None]:
    """Run without waiting for the default executor at the end: a MAVSDK call still blocked in
    its native library after the vehicle went away would otherwise keep the process alive."""
    loop = asyncio.new_event_loop()
    try:
        return loop.run_until_complete(coro)
    finally:
        logging.shutdown()
        sys.stdout.flush()
        sys.stderr.flush()


def _dump_tasks() -> None:
    """SIGUSR1: log every asyncio task's stack (what is a companion waiting for?)."""
    for task in asyncio.all_tasks():
        frames = task.get_stack()
        where = " <- ".join(f"{f.f_code.co_name}:{f.f_lineno}" for f in frames[::-1])
        log.warning("task %s: %s", task.get_name(), where or "(no frames)")


async def _fly(
    config: MissionConfig,
    url: str,
    backend: Backend,
    *,
    tlog: bool,
    mqtt: MqttSpec | None,
    signing_key: bytes | None,
    sensor_source: SensorSourceKind,
) -> tuple[str, MissionExit | None]:
    link = make_link(
        backend,
        url=url,
        target_system=config.system_id,
        tlog=config.tlog_path() if tlog else None,
        signing_key=signing_key,
    )
    options = {f.name: getattr(config, f.name) for f in fields(config)}
    del options["profile"], options["vehicle"]
    async with fly(
        config.profile, config.vehicle, link, mqtt=mqtt, sensor_source=sensor_source, **options
    ) as flight:
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, flight.stop)
        loop.add_signal_handler(signal.SIGUSR1, _dump_tasks)
        reason = await flight.ended()
        return reason, flight.mission.exit


if __name__ == "__main__":
    sys.exit(main())
