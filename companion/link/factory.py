"""Build the link backend a command line names."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from companion.errors import InputError
from companion.link.base import VehicleLink

Backend = Literal["pymavlink", "mavsdk"]
BACKENDS: tuple[Backend, ...] = ("pymavlink", "mavsdk")


def check_signing_support(backend: str, signing_key: bytes | None) -> None:
    """Refuse a signing key for a backend that cannot sign (raises InputError saying why)."""
    if signing_key is not None and backend == "mavsdk":
        raise InputError(
            "MAVLink signing: the mavsdk backend cannot sign (MAVSDK 4 has no message-signing "
            "API); use --backend pymavlink, or unset the key (--signing-key-file / "
            "MDM_MAVLINK_KEY)"
        )


def make_link(
    backend: Backend,
    *,
    url: str,
    target_system: int,
    tlog: Path | None,
    signing_key: bytes | None = None,
) -> VehicleLink:
    """A closed link of the given backend; ``open`` it (or use ``async with``).

    Raises:
        InputError: ``url`` is not a connection address, ``backend`` is unknown, or a
            signing key was given to a backend that cannot sign.
    """
    check_signing_support(backend, signing_key)
    if backend == "pymavlink":
        from companion.link.pymavlink_link import PymavlinkLink

        return PymavlinkLink(
            url=url, target_system=target_system, tlog=tlog, signing_key=signing_key
        )
    if backend == "mavsdk":
        from companion.link.mavsdk_link import MavsdkLink

        return MavsdkLink(url=url, target_system=target_system, tlog=tlog)
    raise InputError(f"unknown backend {backend!r}; allowed: {', '.join(BACKENDS)}")
