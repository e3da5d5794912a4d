"""`companion fleet --gcs udpout:HOST:PORT`: every emulated vehicle's MAVLink to one ground
station (QGroundControl, MAVProxy) as the emulator's --gcs output."""

from __future__ import annotations

import ipaddress


def parse_gcs(value: str) -> tuple[str, int]:
    """``udpout:HOST:PORT`` -> (host, port); HOST an IPv4 address (the emulator sends there)."""
    scheme, _, rest = value.partition(":")
    host, _, port = rest.rpartition(":")
    if scheme != "udpout" or not host or not port:
        raise ValueError(
            f"--gcs {value!r}: expected udpout:HOST:PORT (e.g. udpout:127.0.0.1:14550)"
        )
    try:
        ipaddress.IPv4Address(host)
    except ValueError:
        raise ValueError(f"--gcs {value!r}: HOST must be an IPv4 address, got {host!r}") from None
    if not port.isdigit() or not 1 <= int(port) <= 65535:
        raise ValueError(f"--gcs {value!r}: the port must be a number 1-65535")
    return host, int(port)


def emulator_gcs_args(value: str | None) -> list[str]:
    """The sim-vehicle flags for ``--gcs`` (none without it)."""
    if value is None:
        return []
    host, port = parse_gcs(value)
    return ["--gcs", "--gcs-host", host, "--gcs-port", str(port)]
