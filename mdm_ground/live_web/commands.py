"""`companion watch` and `companion map --web`: build the page and serve it."""

from __future__ import annotations

import argparse
import asyncio
import time
from pathlib import Path

from companion.telemetry.mqtt.cli_args import mqtt_spec
from companion.telemetry.mqtt.settings import settings_for
from companion.telemetry.mqtt.topics import default_prefix
from mdm_ground.live_web.access import is_loopback, resolve_access
from mdm_ground.live_web.cli_args import check_tiles, parse_web
from mdm_ground.live_web.fleet_state import FleetState
from mdm_ground.live_web.mqtt_feed import MqttFeed
from mdm_ground.live_web.replay import Replay
from mdm_ground.live_web.scene import scene
from mdm_ground.live_web.server import LivePage
from mdm_ground.live_web.serving import serve
from mdm_profiles import MissionProfile, load_profile


def watch_command(args: argparse.Namespace) -> int:
    """`companion watch`: serve the page until SIGINT or SIGTERM."""
    profile = load_profile(args.profile)
    spec = mqtt_spec(args, profile.mqtt)
    if spec is None:
        raise ValueError(
            "companion watch reads the team's MQTT topics: give --mqtt HOST[:PORT] "
            "(or a profile with an mqtt: section)"
        )
    if not args.stale_after > 0:
        raise ValueError(f"--stale-after {args.stale_after}: must be > 0 wall s")
    host, port = parse_web(args.web)
    access, generated = resolve_access(
        host, read_only=args.web_read_only, token_file=args.web_token_file
    )
    state = FleetState(profile, show_targets=args.show_targets, stale_after=args.stale_after)
    feed = MqttFeed(settings_for(spec, 0), spec.topic_prefix or default_prefix(profile.name), state)
    vehicles = args.vehicles or profile.fleet.vehicles
    shown = scene(
        profile,
        vehicles=vehicles,
        show_targets=args.show_targets,
        tiles=check_tiles(args.web_tiles),
    )
    page = LivePage(shown, access, state=state, feed=feed, clock=time.time)
    asyncio.run(serve(page, host, port, token_printed=generated))
    return 0


def replay_command(run_dir: Path, profile: MissionProfile, web: str, tiles: str | None) -> int:
    """`companion map --web RUN_DIR`: the run on the page with a time slider."""
    host, port = parse_web(web)
    replay = Replay(run_dir, profile, show_targets=True)
    access, _ = resolve_access(host, read_only=True, token_file=None)
    shown = scene(
        profile, vehicles=len(replay.vehicles), show_targets=True, tiles=check_tiles(tiles)
    )
    page = LivePage(shown, access, replay=replay)
    if not is_loopback(host):
        print(f"web: serving {run_dir} beyond loopback, read-only", flush=True)
    asyncio.run(serve(page, host, port, token_printed=False))
    return 0
