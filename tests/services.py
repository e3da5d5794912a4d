"""The services tests need from outside the package (the MQTT broker and its clients, a
Docker engine, SITL builds, Chromium): whether each is here, and what a test does when one is
not: it skips, naming what is missing; under ``CI=true`` it fails instead, since CI
(``.ci/run``) provides every one of them and a skip there would hide a broken setup.

``python -m tests.services`` lists them and exits 1 when one is missing (``.ci/run`` runs it
before the tests)."""

from __future__ import annotations

import os
import shutil
import socket
import sys
from collections.abc import Callable
from typing import NoReturn

import pytest

from tests import sitl
from tests.docker import engine

MQTT_PORT = 1883
"""The broker the MQTT tests share: the user's, or the one ``.ci/run`` starts."""
_INSTALL_MOSQUITTO = "README 'Tests': `sudo apt-get install mosquitto mosquitto-clients`"


def in_ci() -> bool:
    """Whether this run is CI's (``CI=true``, as GitHub Actions and ``.ci/run`` set it)."""
    return os.environ.get("CI", "").strip().lower() in ("true", "1", "yes")


def missing(what: str) -> NoReturn:
    """Skip the test because ``what`` is missing, or fail it under ``CI=true``."""
    if in_ci():
        pytest.fail(f"CI=true and {what}", pytrace=False)
    pytest.skip(what)


def mqtt_clients_missing() -> str | None:
    """Why mosquitto_sub / mosquitto_pub (the tests watch and command with them) cannot run."""
    for tool in ("mosquitto_sub", "mosquitto_pub"):
        if shutil.which(tool) is None:
            return f"no {tool} on PATH ({_INSTALL_MOSQUITTO})"
    return None


def broker_missing() -> str | None:
    """Why the shared broker on 127.0.0.1:``MQTT_PORT`` cannot be used, or None."""
    with socket.socket() as s:
        if s.connect_ex(("127.0.0.1", MQTT_PORT)) != 0:
            return f"no MQTT broker listens on 127.0.0.1:{MQTT_PORT} ({_INSTALL_MOSQUITTO})"
    return mqtt_clients_missing()


def mosquitto_missing() -> str | None:
    """Why a test cannot start a broker of its own (the ``mosquitto`` binary), or None."""
    if shutil.which("mosquitto") is None:
        return f"no mosquitto on PATH ({_INSTALL_MOSQUITTO})"
    return mqtt_clients_missing()


def chromium_missing() -> str | None:
    """Why headless Chromium cannot be driven (``chromium`` and ``chromedriver`` on PATH)."""
    for tool in ("chromium", "chromedriver"):
        if shutil.which(tool) is None:
            return f"no {tool} on PATH (`sudo apt-get install chromium chromium-driver`)"
    return None


def _sitl_missing(kind: sitl.Kind) -> Callable[[], str | None]:
    return lambda: None if sitl.sitl_dir(kind) is not None else sitl.skip_reason(kind)


SERVICES: dict[str, Callable[[], str | None]] = {
    "broker": broker_missing,
    "mosquitto": mosquitto_missing,
    "docker": engine.missing_engine,
    "chromium": chromium_missing,
    "arducopter": _sitl_missing("arducopter"),
    "px4": _sitl_missing("px4"),
}
"""Each service, and what tells why it is missing (None: it is here)."""


def main() -> int:
    """Print each service and whether it is here; 1 when one is missing."""
    reasons = {name: check() for name, check in SERVICES.items()}
    for name, reason in reasons.items():
        print(f"{name:<11} {'ok' if reason is None else 'MISSING: ' + reason}")
    return 1 if any(reasons.values()) else 0


if __name__ == "__main__":
    sys.exit(main())
