"""The live page of a fleet run (--web): a `companion watch` process beside the companions,
which also runs the embedded MQTT broker when the run has no broker of its own."""

from __future__ import annotations

import re
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from mdm_ground.errors import GroundError
from mdm_ground.fleet import processes
from mdm_ground.fleet.options import FleetOptions

WEB_LOG = "web.log"
BROKER_ACCOUNTS = "broker-accounts"
"""The embedded broker's accounts in the run directory, removed at the end of the run."""
_START_S = 60.0
"""Wall seconds the page has to print its address before the run is refused."""
_BROKER_LINE = re.compile(r"broker: (\S+):(\d+) \(embedded, ([^;]+);")


class WebPageError(GroundError, ValueError):
    """The live page did not start (its port is taken, the broker flags are wrong ...)."""


@dataclass(frozen=True)
class EmbeddedBrokerInfo:
    """Where the page's embedded broker listens, and the accounts it made for the run."""

    host: str
    port: int
    server: str
    """``amqtt X.Y.Z``"""
    accounts: Path

    def companion_args(self) -> tuple[str, ...]:
        """The --mqtt flags of every companion: its own account (``uav{vehicle}``)."""
        return (
            "--mqtt", f"{self.host}:{self.port}", "--mqtt-username", "uav{vehicle}",
            "--mqtt-password-file", str(self.accounts / "uav{vehicle}.pw"),
        )  # fmt: skip


@dataclass(frozen=True)
class WebPage:
    """The page's process and, when it runs one, its embedded broker."""

    process: subprocess.Popen[bytes]
    broker: EmbeddedBrokerInfo | None


def start_page(
    o: FleetOptions, vehicles: int, *, emulated: bool, env: dict[str, str]
) -> WebPage | None:
    """Start the page (None without --web) and return once it serves; its address (and
    token, when it made one) is in ``web.log`` and said on stderr."""
    if not o.web:
        return None
    virtual = (o.sensor_source or "") == "virtual"
    accounts = o.out / BROKER_ACCOUNTS
    command = [
        sys.executable, "-m", "companion.cli", "watch", "--profile", o.profile,
        "--vehicles", str(vehicles), *o.web, *o.mqtt_args,
        *(["--broker-accounts", str(accounts)] if o.embedded_broker else []),
        # the run knows its targets when it simulates them
        *(["--show-targets"] if emulated or virtual else []),
    ]  # fmt: skip
    log = o.out / WEB_LOG
    page = processes.start(command, log, env, append=o.resume)
    deadline = time.monotonic() + _START_S
    while time.monotonic() < deadline:
        text = log.read_text(encoding="utf-8", errors="replace")
        lines = text.splitlines()
        address = next((line for line in lines if line.startswith("web: http")), None)
        if address is not None:
            broker = _BROKER_LINE.search(text) if o.embedded_broker else None
            if o.embedded_broker and broker is None:
                processes.stop(page, 2.0)
                raise WebPageError(f"--web: the page said no embedded broker (see {log})")
            info = None if broker is None else EmbeddedBrokerInfo(
                broker.group(1), int(broker.group(2)), broker.group(3), accounts
            )  # fmt: skip
            if info is not None:
                print(
                    f"fleet: embedded MQTT broker {info.host}:{info.port} ({info.server}) in "
                    "the live page's process; an account per companion",
                    file=sys.stderr,
                    flush=True,
                )
            print(
                f"fleet: live page {address.removeprefix('web: ')} (log {log})",
                file=sys.stderr,
                flush=True,
            )
            return WebPage(page, info)
        if page.poll() is not None:
            last = lines[-1] if lines else "(no output)"
            raise WebPageError(f"--web: the live page did not start: {last} (see {log})")
        time.sleep(0.1)
    processes.stop(page, 2.0)
    raise WebPageError(f"--web: the live page did not start within {_START_S:.0f} s (see {log})")
