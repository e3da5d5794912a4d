"""`companion fleet` on the command line: options in, summary (or JSON) and exit status out."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from companion.fence_from_profile import guidance_fence
from companion.mission.core_for import LAWNMOWER_KINDS
from companion.mission.lawnmower_core import LawnmowerCore
from companion.telemetry.mqtt.cli_args import mqtt_argv, mqtt_spec
from mdm_core.search.pso import VARIANTS
from mdm_ground.fleet.gcs import parse_gcs
from mdm_ground.fleet.options import FleetOptions
from mdm_ground.fleet.runner import run_fleet
from mdm_ground.fleet.summary import exit_status, summary_lines
from mdm_ground.live_web.cli_args import check_tiles, parse_web, web_argv
from mdm_profiles import load_profile
from mdm_provenance import extras


def fleet_command(args: argparse.Namespace) -> int:
    """`companion fleet`: run, print a summary (or JSON); 0 only for a complete run."""
    if args.vehicles_file is None and args.sitl is None:  # the emulator flies the team
        extras.require("companion fleet", "emulator")
    out = args.out or Path("runs") / time.strftime("fleet-%Y%m%d-%H%M%S")
    profile = load_profile(args.profile)
    # Bad --mqtt* flags, or a swarm kind without a broker, fail here, not N times.
    external = mqtt_spec(args, profile.mqtt) is not None
    if not external and profile.policy.kind in VARIANTS:
        raise ValueError(
            f"profile {profile.name!r}: policy.kind {profile.policy.kind!r} shares the swarm's "
            "bests over MQTT; configure a broker (--mqtt HOST[:PORT] or the profile's mqtt:)"
        )
    if profile.policy.kind in LAWNMOWER_KINDS:  # every strip inside the fence, not N refusals
        fence = guidance_fence(profile)
        for i in range(profile.fleet.vehicles if args.vehicles is None else args.vehicles):
            try:
                LawnmowerCore(profile, args.seed, i, fence)
            except ValueError as exc:
                raise ValueError(f"profile {profile.name!r}, vehicle {i}: {exc}") from None
    web = _web_argv(args)
    if args.gcs is not None:
        parse_gcs(args.gcs)
        if args.vehicles_file is not None or args.sitl is not None:
            raise ValueError(
                "--gcs forwards the emulator's vehicles; SITL and real vehicles have "
                "their own ground-station ports (docs/live_web.md, 'Ground station')"
            )
    opts = FleetOptions(
        profile=args.profile,
        out=out,
        vehicles=args.vehicles,
        speedup=args.speedup,
        duration=args.duration,
        backend=args.backend,
        persona=args.persona,
        setpoints=args.setpoints,
        seed=args.seed,
        base_port=args.base_port,
        quiet=args.quiet or args.json,
        land_wait=args.land_wait,
        flight_log_wait=args.flight_log_wait,
        resume=args.resume,
        mqtt_args=tuple(mqtt_argv(args)),
        signing_key_file=args.signing_key_file,
        lockstep=args.lockstep,
        sensor_source=args.sensor_source,
        vehicles_file=args.vehicles_file,
        sitl=args.sitl,
        sitl_speedup=args.sitl_speedup,
        link_timeout=args.link_timeout,
        web=web,
        embedded_broker=bool(web) and not external,
        gcs=args.gcs,
    )
    started = time.perf_counter()
    result = run_fleet(opts)
    wall = time.perf_counter() - started
    if args.json:
        print(json.dumps(result.as_json() | {"wall_s": round(wall, 1)}, default=str))
    else:
        print("\n" + "\n".join(summary_lines(result, out, wall)))
    return exit_status(result)


def _web_argv(args: argparse.Namespace) -> tuple[str, ...]:
    """The `companion watch` flags of --web (checked here, before anything starts)."""
    if args.web is None:
        if args.web_read_only or args.web_token_file or args.web_tiles:
            raise ValueError(
                "--web-read-only, --web-token-file and --web-tiles need --web [HOST:]PORT"
            )
        return ()
    parse_web(args.web)
    check_tiles(args.web_tiles)
    return ("--web", args.web, *web_argv(args))
