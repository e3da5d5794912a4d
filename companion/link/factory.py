"""Build the link backend a command line names."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from companion.link.base import VehicleLink
from companion.link.geo import LocalFrame

Backend = Literal["pymavlink", "mavsdk"]
BACKENDS: tuple[Backend, ...] = ("pymavlink", "mavsdk")


def make_link(
    backend: Backend,
    *,
    url: str,
    target_system: int,
    tlog: Path | None,
    frame: LocalFrame | None = None,
) -> VehicleLink:
    """A closed link of the given backend; ``open`` it (or use ``async with``)."""
    if backend == "pymavlink":
        from companion.link.pymavlink_link import PymavlinkLink

        return PymavlinkLink(url=url, target_system=target_system, tlog=tlog, frame=frame)
    if backend == "mavsdk":
        from companion.link.mavsdk_link import MavsdkLink

        return MavsdkLink(url=url, target_system=target_system, tlog=tlog)
    raise ValueError(f"unknown backend {backend!r}; allowed: {', '.join(BACKENDS)}")
