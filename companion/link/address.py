"""Parse a connection URL: udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT (also with '://'),
and a serial device: serial:DEVICE:BAUD (also MAVSDK's serial://DEVICE:BAUD, and pymavlink's and
MAVProxy's DEVICE,BAUD)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from companion.errors import InputError

Scheme = Literal["udpin", "udpout", "tcp", "serial"]
_SCHEMES: tuple[Scheme, ...] = ("udpin", "udpout", "tcp", "serial")
BAUDS: tuple[int, ...] = (
    9600, 19200, 38400, 57600, 115200, 230400, 460800, 500000, 921600, 1000000, 1500000,
    2000000, 3000000,
)  # fmt: skip
"""The serial rates accepted: those Linux's termios names (``termios.B<rate>``)."""


@dataclass(frozen=True)
class Address:
    """Where a link listens or connects. A serial link's ``host`` is the device's path and its
    ``port`` the baud rate."""

    scheme: Scheme
    host: str
    port: int

    @property
    def is_serial(self) -> bool:
        return self.scheme == "serial"

    def url(self) -> str:
        """The pymavlink-style spelling, scheme:host:port."""
        return f"{self.scheme}:{self.host}:{self.port}"

    def mavsdk_url(self) -> str:
        """The MAVSDK spelling, scheme://host:port (tcp -> tcpout; serial://DEVICE:BAUD)."""
        scheme = "tcpout" if self.scheme == "tcp" else self.scheme
        return f"{scheme}://{self.host}:{self.port}"


def parse_address(url: str) -> Address:
    """An Address from a URL; raises InputError (a ValueError) naming what is wrong."""
    text = url.strip().replace("://", ":")
    if text.startswith("serial:") or (text.startswith("/") and "," in text):
        return _serial(url, text)
    parts = text.split(":")
    if len(parts) != 3:
        raise InputError(f"connection {url!r}: expected SCHEME:HOST:PORT, e.g. udpin:0.0.0.0:14540")
    scheme, host, port = parts
    if scheme == "tcpout":
        scheme = "tcp"
    if scheme not in _SCHEMES:
        raise InputError(f"connection {url!r}: scheme {scheme!r} not one of {', '.join(_SCHEMES)}")
    try:
        number = int(port)
    except ValueError:
        raise InputError(f"connection {url!r}: port {port!r} is not a number") from None
    if not 0 < number < 65536:
        raise InputError(f"connection {url!r}: port {number} out of range 1..65535")
    return Address(scheme, host or "0.0.0.0", number)


def _serial(url: str, text: str) -> Address:
    """serial:DEVICE:BAUD, or DEVICE,BAUD (pymavlink's and MAVProxy's spelling)."""
    if text.startswith("serial:"):
        device, sep, rate = text.removeprefix("serial:").rpartition(":")
    else:
        device, sep, rate = text.rpartition(",")
    if not sep or not device:
        raise InputError(
            f"connection {url!r}: expected serial:DEVICE:BAUD, e.g. serial:/dev/ttyAMA0:921600"
        )
    try:
        baud = int(rate)
    except ValueError:
        raise InputError(f"connection {url!r}: baud rate {rate!r} is not a number") from None
    if baud not in BAUDS:
        raise InputError(
            f"connection {url!r}: baud rate {baud} not one of {', '.join(map(str, BAUDS))}"
        )
    return Address("serial", device, baud)
