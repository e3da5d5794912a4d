"""The live page of a fleet run (--web): a `companion watch` process beside the companions."""

from __future__ import annotations

import subprocess
import sys
import time

from mdm_ground.errors import GroundError
from mdm_ground.fleet import processes
from mdm_ground.fleet.options import FleetOptions

WEB_LOG = "web.log"
_START_S = 60.0
"""Wall seconds the page has to print its address before the run is refused."""


class WebPageError(GroundError, ValueError):
    """The live page did not start (its port is taken, the broker flags are wrong ...)."""


def start_page(
    o: FleetOptions, vehicles: int, *, emulated: bool, env: dict[str, str]
) -> subprocess.Popen[bytes] | None:
    """Start the page (None without --web) and return once it serves; its address (and
    token, when it made one) is in ``web.log`` and said on stderr."""
    if not o.web:
        return None
    virtual = (o.sensor_source or "") == "virtual"
    command = [
        sys.executable, "-m", "companion.cli", "watch", "--profile", o.profile,
        "--vehicles", str(vehicles), *o.web, *o.mqtt_args,
        # the run knows its targets when it simulates them
        *(["--show-targets"] if emulated or virtual else []),
    ]  # fmt: skip
    log = o.out / WEB_LOG
    page = processes.start(command, log, env, append=o.resume)
    deadline = time.monotonic() + _START_S
    while time.monotonic() < deadline:
        lines = log.read_text(encoding="utf-8", errors="replace").splitlines()
        address = next((line for line in lines if line.startswith("web: http")), None)
        if address is not None:
            print(
                f"fleet: live page {address.removeprefix('web: ')} (log {log})",
                file=sys.stderr,
                flush=True,
            )
            return page
        if page.poll() is not None:
            last = lines[-1] if lines else "(no output)"
            raise WebPageError(f"--web: the live page did not start: {last} (see {log})")
        time.sleep(0.1)
    processes.stop(page, 2.0)
    raise WebPageError(f"--web: the live page did not start within {_START_S:.0f} s (see {log})")
