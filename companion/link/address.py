"""Parse a connection URL: udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT (also with '://')."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from companion.errors import InputError

Scheme = Literal["udpin", "udpout", "tcp"]
_SCHEMES: tuple[Scheme, ...] = ("udpin", "udpout", "tcp")


@dataclass(frozen=True)
class Address:
    """Where a link listens or connects."""

    scheme: Scheme
    host: str
    port: int

    def url(self) -> str:
        """The pymavlink-style spelling, scheme:host:port."""
        return f"{self.scheme}:{self.host}:{self.port}"

    def mavsdk_url(self) -> str:
        """The MAVSDK spelling, scheme://host:port (tcp -> tcpout)."""
        scheme = "tcpout" if self.scheme == "tcp" else self.scheme
        return f"{scheme}://{self.host}:{self.port}"


def parse_address(url: str) -> Address:
    """An Address from a URL; raises InputError (a ValueError) naming what is wrong."""
    text = url.strip().replace("://", ":")
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
