"""`companion watch` and `companion map --web`: build the page and serve it."""

from __future__ import annotations

import argparse
import asyncio
import shutil
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from companion.telemetry.mqtt.cli_args import mqtt_spec
from companion.telemetry.mqtt.settings import settings_for
from companion.telemetry.mqtt.topics import default_prefix
from mdm_ground.live_web.access import is_loopback, resolve_access
from mdm_ground.live_web.cli_args import DEFAULT_BROKER, check_tiles, parse_web
from mdm_ground.live_web.fleet_state import FleetState
from mdm_ground.live_web.mqtt_feed import MqttFeed
from mdm_ground.live_web.replay import Replay
from mdm_ground.live_web.scene import scene
from mdm_ground.live_web.server import LivePage
from mdm_ground.live_web.serving import serve
from mdm_profiles import MissionProfile, load_profile
from mdm_profiles.mqtt_spec import MqttSpec


def watch_command(args: argparse.Namespace) -> int:
    """`companion watch`: serve the page (and, without a broker given, the embedded one)
    until SIGINT or SIGTERM."""
    profile = load_profile(args.profile)
    spec = mqtt_spec(args, profile.mqtt)
    if not args.stale_after > 0:
        raise ValueError(f"--stale-after {args.stale_after}: must be > 0 wall s")
    host, port = parse_web(args.web)
    vehicles = args.vehicles or profile.fleet.vehicles
    if spec is not None and (args.broker_bind or args.broker_accounts):
        raise ValueError(
            "--broker-bind and --broker-accounts are the embedded broker's, started only "
            "without --mqtt (and without a profile's mqtt: section)"
        )
    broker = parse_web(args.broker_bind or DEFAULT_BROKER, "--broker-bind")
    access, generated = resolve_access(
        host, read_only=args.web_read_only, token_file=args.web_token_file
    )
    tiles = check_tiles(args.web_tiles)

    def page_on(spec: MqttSpec, described: str) -> LivePage:
        state = FleetState(profile, show_targets=args.show_targets, stale_after=args.stale_after)
        prefix = spec.topic_prefix or default_prefix(profile.name)
        feed = MqttFeed(settings_for(spec, 0), prefix, state)
        shown = scene(profile, vehicles=vehicles, show_targets=args.show_targets, tiles=tiles) | {
            "broker": described
        }
        return LivePage(shown, access, state=state, feed=feed, clock=time.time)

    if spec is not None:
        page = page_on(spec, f"{spec.host}:{spec.port}")
        asyncio.run(serve(page, host, port, token_printed=generated))
        return 0
    asyncio.run(
        _serve_with_broker(page_on, broker, args.broker_accounts, vehicles, (host, port), generated)
    )
    return 0


async def _serve_with_broker(
    page_on: Callable[[MqttSpec, str], LivePage],
    bind: tuple[str, int],
    folder: Path | None,
    vehicles: int,
    web: tuple[str, int],
    token_printed: bool,
) -> None:
    """The embedded broker on ``bind`` with fresh accounts in ``folder`` (None: a temporary
    one), the page its ``operator``; both until SIGINT or SIGTERM."""
    from mdm_ground.broker.accounts import create_accounts
    from mdm_ground.broker.embedded import EmbeddedBroker, server_name

    temporary = folder is None
    accounts = create_accounts(
        Path(tempfile.mkdtemp(prefix="mdm-broker-")) if folder is None else folder, vehicles
    )
    try:
        async with EmbeddedBroker(*bind, password_file=accounts.passwd) as broker:
            # `companion fleet` reads this line for its companions' --mqtt
            print(
                f"broker: {broker.address} (embedded, {server_name()}; accounts uav0 .. "
                f"uav{vehicles - 1}, operator, monitor; their passwords in "
                f"{accounts.folder}/NAME.pw)",
                flush=True,
            )
            if not is_loopback(broker.host):
                print("broker: beyond loopback, plain MQTT: passwords cross the network in clear",
                      file=sys.stderr, flush=True)  # fmt: skip
            operator = MqttSpec(
                host=broker.host,
                port=broker.port,
                username="operator",
                password_file=str(accounts.password_file("operator")),
            )
            page = page_on(operator, f"embedded {server_name()} on {broker.address}")
            await serve(page, *web, token_printed=token_printed)
    finally:
        if temporary:
            shutil.rmtree(accounts.folder, ignore_errors=True)


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
