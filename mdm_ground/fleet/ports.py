"""The UDP ports of one fleet on this machine: a free block by default, a busy one refused.

A fleet of N vehicles uses 2N consecutive ports from its base: the companion of vehicle i
listens on base+i (on every interface, as `companion run` binds), the emulator's vehicle i on
127.0.0.1:base+N+i. A bind test cannot see a stray emulator that only *sends* to a port (it
binds ports of its own), so an explicit base is also listened on for a moment, and the default
block is taken from the operating system's ephemeral range, away from the well-known
14540+ and 14580+ that other MAVLink tools send to.
"""

from __future__ import annotations

import contextlib
import select
import socket
from dataclasses import dataclass

from mdm_ground.errors import GroundError

_LISTEN_S = 1.2
"""How long an explicit base's companion ports are listened on: an emulator's vehicle sends a
HEARTBEAT every second, so one sending there is heard."""
_ATTEMPTS = 50


class PortError(GroundError, ValueError):
    """The requested ports cannot be used (the message names the port and why)."""


@dataclass(frozen=True)
class PortBlock:
    """Where the companions and the emulator's vehicles listen."""

    base: int
    vehicles: int

    @property
    def emulator_base(self) -> int:
        return self.base + self.vehicles

    def describe(self) -> str:
        n = self.vehicles
        return (
            f"UDP ports: companions {self.base}..{self.base + n - 1}, "
            f"emulator 127.0.0.1:{self.emulator_base}..{self.emulator_base + n - 1}"
        )


def _bind_all(block: PortBlock) -> list[socket.socket]:
    """Bind every port of ``block`` as its users will; OSError names the first busy one."""
    held: list[socket.socket] = []
    try:
        for i in range(block.vehicles):
            for host, port, who in (
                ("0.0.0.0", block.base + i, f"vehicle {i}'s companion"),
                ("127.0.0.1", block.emulator_base + i, f"the emulator's vehicle {i}"),
            ):
                s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
                held.append(s)
                try:
                    s.bind((host, port))
                except OSError as exc:
                    raise OSError(exc.errno, f"UDP port {port} ({who}): {exc.strerror}") from None
    except BaseException:
        for s in held:
            s.close()
        raise
    return held


def _first_sender(sockets: list[socket.socket], seconds: float) -> str | None:
    """Who sends to any of ``sockets`` within ``seconds`` (host:port -> our port), else None."""
    ready, _, _ = select.select(sockets, [], [], seconds)
    for s in ready:
        with contextlib.suppress(OSError):
            _, (host, port) = s.recvfrom(2048)
            return f"{host}:{port} sends to UDP port {s.getsockname()[1]}"
    return None


def check_base_port(base: int, vehicles: int) -> PortBlock:
    """An explicit ``--base-port``: every port free and nobody already sending to them."""
    block = PortBlock(base, vehicles)
    top = block.emulator_base + vehicles - 1
    if base < 1024 or top > 65535:
        raise PortError(
            f"--base-port {base}: {vehicles} vehicles need UDP ports {base}..{top}, "
            "which must lie within 1024..65535"
        )
    try:
        held = _bind_all(block)
    except OSError as exc:
        raise PortError(
            f"--base-port {base}: {exc.strerror}; choose another base or leave --base-port "
            "out for a free block"
        ) from None
    try:
        stray = _first_sender(held[0::2], _LISTEN_S)
    finally:
        for s in held:
            s.close()
    if stray is not None:
        raise PortError(
            f"--base-port {base}: {stray} (another emulator or vehicle is already talking "
            "there); choose another base or leave --base-port out for a free block"
        )
    return block


def free_port_block(vehicles: int) -> PortBlock:
    """A block of 2 x ``vehicles`` consecutive free UDP ports, from the ephemeral range."""
    for _ in range(_ATTEMPTS):
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
            probe.bind(("127.0.0.1", 0))
            base = int(probe.getsockname()[1])
        block = PortBlock(base, vehicles)
        if block.emulator_base + vehicles - 1 > 65535:
            continue
        try:
            held = _bind_all(block)
        except OSError:
            continue
        for s in held:
            s.close()
        return block
    raise PortError(f"no block of {2 * vehicles} free UDP ports found in {_ATTEMPTS} tries")
