"""The markers a test gets from the fixtures it uses (never by hand), so that a new test that
asks for a SITL instance, a broker, a browser, a Docker image, a fleet's processes or a fresh
install is selected and deselected with its kind:
``pytest -m "not sitl and not docker and not browser and not install"``.

A test with none of them is the socket-light core."""

from __future__ import annotations

from collections.abc import Iterable

MARKERS: dict[str, str] = {
    "sitl": "flies a real ArduCopter or PX4 SITL instance (fixtures arducopter, px4, sitl_*)",
    "docker": "builds or runs Docker images (fixtures docker_*)",
    "broker": "talks to a Mosquitto broker (fixtures mqtt_broker, mosquitto)",
    "browser": "drives headless Chromium (fixture chromium, browser_*)",
    "fleet": "runs several processes: emulator and companions (fixtures fleet_*)",
    "install": "installs the package into a fresh virtual environment (fixtures install_*)",
}
"""Marker -> its description, as registered with pytest."""

_EXACT: dict[str, str] = {
    "arducopter": "sitl",
    "px4": "sitl",
    "mqtt_broker": "broker",
    "mosquitto": "broker",
    "chromium": "browser",
}
_PREFIXES: tuple[tuple[str, str], ...] = (
    ("sitl_", "sitl"),
    ("docker_", "docker"),
    ("browser_", "browser"),
    ("fleet_", "fleet"),
    ("install_", "install"),
)


def markers_for(fixture_names: Iterable[str]) -> set[str]:
    """The markers a test using ``fixture_names`` (its whole fixture closure) carries."""
    found = set()
    for name in fixture_names:
        if name in _EXACT:
            found.add(_EXACT[name])
        found.update(marker for prefix, marker in _PREFIXES if name.startswith(prefix))
    return found
