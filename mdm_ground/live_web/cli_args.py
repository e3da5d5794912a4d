"""The command line of `companion watch` and the --web flags it shares with `companion fleet`
and `companion map` (no aiohttp here: `companion run` imports this module's neighbours)."""

from __future__ import annotations

import argparse
from pathlib import Path

from companion.telemetry.mqtt.cli_args import add_mqtt_arguments

DEFAULT_WEB = "127.0.0.1:8765"
DEFAULT_BROKER = "127.0.0.1:0"
STALE_AFTER_S = 5.0


def parse_web(value: str, flag: str = "--web") -> tuple[str, int]:
    """``PORT``, ``HOST:PORT`` or ``[IPV6]:PORT`` -> (host, port); host 127.0.0.1 if not given."""
    host, sep, port = value.rpartition(":")
    if not sep:
        host = "127.0.0.1"
    host = host.strip("[]") if host.startswith("[") else host
    if not host or (":" in host and not value.startswith("[")):
        raise ValueError(f"{flag} {value!r}: expected PORT, HOST:PORT or [IPV6]:PORT")
    if not port.isdigit() or not 0 <= int(port) <= 65535:
        raise ValueError(f"{flag} {value!r}: the port must be a number 0-65535 (0: any free one)")
    return host, int(port)


def check_tiles(template: str | None) -> str | None:
    """A map-tile URL template (``https://tiles.example/{z}/{x}/{y}.png``), checked."""
    if template is None:
        return None
    missing = [k for k in ("{z}", "{x}", "{y}") if k not in template]
    if not template.startswith(("http://", "https://")) or missing:
        raise ValueError(
            f"--web-tiles {template!r}: expected an http(s) URL with {{z}}, {{x}} "
            f"and {{y}}{'; it lacks ' + ', '.join(missing) if missing else ''}"
        )
    return template


def add_tiles_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--web-tiles",
        metavar="URL",
        help="map tiles under the page, from your own tile server "
        "(http://HOST/{z}/{x}/{y}.png; the browser loads them); default none",
    )


def add_web_arguments(p: argparse.ArgumentParser) -> None:
    """--web-read-only, --web-token-file and --web-tiles (--web itself differs per command)."""
    add_tiles_argument(p)
    p.add_argument(
        "--web-read-only", action="store_true", help="the page shows the team but sends no commands"
    )
    p.add_argument(
        "--web-token-file",
        type=Path,
        metavar="PATH",
        help="token for commands, its first line (default: $MDM_WEB_TOKEN; a bind "
        "beyond loopback without either gets a random one, printed at start)",
    )


def web_argv(args: argparse.Namespace) -> list[str]:
    """The same flags again, for the `companion watch` a fleet starts."""
    return [
        *(["--web-read-only"] if args.web_read_only else []),
        *(["--web-token-file", str(args.web_token_file)] if args.web_token_file else []),
        *(["--web-tiles", args.web_tiles] if args.web_tiles else []),
    ]


def add_watch_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Register `companion watch`."""
    p = sub.add_parser("watch", help="a live web page of a team from its MQTT topics")
    p.add_argument("--profile", default="paper-fixed", help="the profile the team flies")
    p.add_argument(
        "--web",
        default=DEFAULT_WEB,
        metavar="[HOST:]PORT",
        help=f"where the page is served (default {DEFAULT_WEB}; port 0: any free)",
    )
    p.add_argument("--vehicles", type=int, help="team size shown (default: the profile's)")
    p.add_argument(
        "--show-targets",
        action="store_true",
        help="draw the profile's targets (an emulator or virtual-sensor run)",
    )
    p.add_argument(
        "--stale-after",
        type=float,
        default=STALE_AFTER_S,
        help="wall s without a message after which a vehicle is shown stale",
    )
    add_web_arguments(p)
    g = p.add_argument_group("the embedded MQTT broker (without --mqtt or the profile's mqtt:)")
    g.add_argument(
        "--broker-bind",
        metavar="[HOST:]PORT",
        help=f"where it listens (default {DEFAULT_BROKER}: loopback, a free port, printed)",
    )
    g.add_argument(
        "--broker-accounts",
        type=Path,
        metavar="DIR",
        help="write its accounts there: the password file and each account's password in "
        "NAME.pw, uav0.pw ... operator.pw monitor.pw (default: a private temporary folder, "
        "removed at exit)",
    )
    add_mqtt_arguments(p)
