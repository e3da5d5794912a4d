"""The sockets under the pymavlink link: UDP in (bound; answers go to the vehicle's address once
it spoke), UDP out, TCP, and a serial device (serial_device.py); bytes in to the link's
callbacks, bytes out as they are."""

from __future__ import annotations

import asyncio
import logging
import os
import socket
from collections.abc import Callable
from typing import Any, cast

from companion.errors import InputError
from companion.link.address import Address
from companion.link.errors import LinkError
from companion.link.serial_device import open_serial

log = logging.getLogger(__name__)

_DRAIN_MAX = 256
"""Datagrams read at once beyond the one asyncio hands over (see :meth:`MavlinkTransport.drain`)."""

Sender = tuple[str | Any, int]
OnDatagram = Callable[[bytes, Sender], None]


class _Protocol(asyncio.DatagramProtocol, asyncio.Protocol):
    def __init__(
        self,
        on_datagram: OnDatagram,
        on_stream: Callable[[bytes], None],
        on_lost: Callable[[], None] = lambda: None,
    ) -> None:
        self.on_datagram = on_datagram
        self.on_stream = on_stream
        self.on_lost = on_lost

    def datagram_received(self, data: bytes, addr: Sender) -> None:
        self.on_datagram(data, addr)

    def data_received(self, data: bytes) -> None:
        self.on_stream(data)

    def connection_lost(self, exc: Exception | None) -> None:
        if exc is not None:
            log.warning("connection lost: %s", exc)
        self.on_lost()


class MavlinkTransport:
    """One link's socket; ``on_datagram`` gets each UDP datagram with its sender, ``on_stream``
    each chunk read from TCP."""

    def __init__(
        self, address: Address, on_datagram: OnDatagram, on_stream: Callable[[bytes], None]
    ) -> None:
        self.address = address
        self._on_datagram = on_datagram
        self._on_stream = on_stream
        self._transport: asyncio.BaseTransport | None = None
        self._serial_out: asyncio.WriteTransport | None = None
        """A serial device's writing half (``_transport`` is its reading half)."""
        self._serial_lost = False
        """The serial device went away (a cable pulled): nothing is sent until it is re-opened."""
        self.sock: socket.socket | None = None
        """The UDP socket (None for TCP or while closed): read directly by :meth:`drain`."""
        self.remote: tuple[str, int] | None = None
        """Where UDP goes: udpout's address; udpin's vehicle, set by the link when it locks to
        the first address that speaks for the target system."""

    @property
    def is_open(self) -> bool:
        return self._transport is not None

    async def open(self) -> None:
        """Bind, or connect.

        Raises:
            LinkError: the address cannot be bound or connected to.
        """
        loop = asyncio.get_running_loop()
        a = self.address

        def protocol() -> _Protocol:
            return _Protocol(self._on_datagram, self._on_stream)

        try:
            if a.scheme in ("udpin", "udpout"):
                # Our own socket (the transport's wrapper cannot read): see drain.
                sock = await _udp_socket(loop, a.host, a.port, bind=a.scheme == "udpin")
                self._transport, _ = await loop.create_datagram_endpoint(protocol, sock=sock)
                self.sock = sock
                if a.scheme == "udpout":
                    self.remote = (a.host, a.port)
            elif a.is_serial:
                await self._open_serial(loop)
            else:
                self._transport, _ = await loop.create_connection(protocol, a.host, a.port)
        except OSError as exc:
            raise LinkError(f"cannot open {a.url()}: {exc}") from exc
        except InputError as exc:  # a serial device gone or busy: retried like a port not up
            raise LinkError(str(exc)) from exc

    async def _open_serial(self, loop: asyncio.AbstractEventLoop) -> None:
        """The device as two pipe transports (reading, writing) over one locked descriptor."""
        fd = open_serial(self.address)
        reader = os.fdopen(fd, "rb", buffering=0)
        writer = os.fdopen(os.dup(fd), "wb", buffering=0)

        def lost() -> None:
            if self._transport is not None and not self._serial_lost:
                log.warning("serial device %s gone", self.address.host)
            self._serial_lost = True
            if self._serial_out is not None:
                self._serial_out.close()

        self._serial_lost = False
        self._transport, _ = await loop.connect_read_pipe(
            lambda: _Protocol(self._on_datagram, self._on_stream, lost), reader
        )
        out, _ = await loop.connect_write_pipe(asyncio.Protocol, writer)
        self._serial_out = out

    def close(self) -> None:
        if self._serial_out is not None:
            self._serial_out.close()
            self._serial_out = None
        if self._transport is not None:
            self._transport.close()
            self._transport = None
        self.sock = None
        if self.address.scheme == "udpin":
            self.remote = None

    def drain(self, receive: Callable[[bytes, Sender], None]) -> None:
        """Read every datagram already waiting into ``receive``. asyncio hands over one
        datagram per loop iteration, so a companion that fell behind a sped-up vehicle would
        answer each stale position in turn (seconds of vehicle time late); read at once, the
        decision loop acts on the newest position only."""
        sock = self.sock
        for _ in range(_DRAIN_MAX if sock is not None else 0):
            try:
                data, addr = sock.recvfrom(65536)  # type: ignore[union-attr]
            except (BlockingIOError, InterruptedError):
                return
            except OSError:  # ICMP port unreachable and the like: the transport reports them
                return
            receive(data, addr)

    def waiting(self) -> bool | None:
        """Whether another datagram waits behind the one handed over (None: the socket
        reported an error, which the transport reports in its turn)."""
        try:
            self.sock.recv(1, socket.MSG_PEEK)  # type: ignore[union-attr]
            return True
        except (BlockingIOError, InterruptedError):
            return False
        except OSError:  # ICMP port unreachable and the like
            return None

    def send(self, buf: bytes) -> bool:
        """``buf`` out; False when it could not go (udpin before the vehicle spoke)."""
        transport = self._transport
        assert transport is not None
        # (selector datagram transports are not DatagramTransport subclasses: go by scheme)
        if self.address.scheme == "udpin":
            if self.remote is None:
                return False  # the vehicle has not spoken yet
            cast(asyncio.DatagramTransport, transport).sendto(buf, self.remote)
        elif self.address.scheme == "udpout":
            cast(asyncio.DatagramTransport, transport).sendto(buf)
        elif self.address.is_serial:
            if self._serial_lost or self._serial_out is None:
                return False  # the device went away: re-opened by the link's reconnect
            self._serial_out.write(buf)
        else:
            cast(asyncio.WriteTransport, transport).write(buf)
        return True


async def _udp_socket(
    loop: asyncio.AbstractEventLoop, host: str, port: int, *, bind: bool
) -> socket.socket:
    """A non-blocking UDP socket bound to (host, port), or connected to it."""
    infos = await loop.getaddrinfo(host, port, type=socket.SOCK_DGRAM)
    if not infos:
        raise OSError(f"cannot resolve {host}")
    family, kind, proto, _, where = infos[0]
    sock = socket.socket(family, kind, proto)
    try:
        sock.setblocking(False)
        if bind:
            sock.bind(where)
        else:
            sock.connect(where)
    except OSError:
        sock.close()
        raise
    return sock
