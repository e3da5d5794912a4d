"""Network endpoints: per-vehicle UDP (PX4 SITL style) and TCP server, and the shared GCS output.

Every endpoint reads in asyncio callbacks as datagrams arrive, so a slow or hostile peer on one
vehicle's port never delays another vehicle. Floods are dropped unread by token buckets: one per
known peer and one shared by every other sender, so garbage from strangers cannot starve a
client the vehicle already talks to.
"""

from __future__ import annotations

import asyncio
import logging
import socket
import time
from collections.abc import Callable
from typing import Any, cast

from sim_vehicle_stub.framing import FrameDecoder, LinkStats
from sim_vehicle_stub.node import VehicleNode

log = logging.getLogger(__name__)

Address = tuple[str, int]
Deliver = Callable[[VehicleNode, list[Any]], None]

_MAX_PEERS = 4
_PEER_TTL = 10.0
_TCP_BACKLOG_LIMIT = 1 << 20


class TokenBucket:
    """Wall-clock rate limit: ``rate`` per second with bursts of ``burst``."""

    def __init__(self, rate: float, burst: float) -> None:
        self.rate, self.burst = rate, burst
        self.tokens = burst
        self.stamp = time.monotonic()

    def allow(self) -> bool:
        now = time.monotonic()
        self.tokens = min(self.burst, self.tokens + (now - self.stamp) * self.rate)
        self.stamp = now
        if self.tokens >= 1.0:
            self.tokens -= 1.0
            return True
        return False


class PeerSet:
    """The configured remote plus up to ``_MAX_PEERS`` other senders of valid MAVLink.

    A slot is held while its sender keeps talking (within ``_PEER_TTL`` s): a newcomer gets a
    free or expired slot and never evicts an active client (real PX4 answers only the first
    sender on a link; the emulator serves a few). Each peer has its own flood bucket; senders
    without a slot share one.
    """

    def __init__(self, remote: Address | None, rate: float, burst: float) -> None:
        self.remote = remote
        self.rate, self.burst = rate, burst
        self.seen: dict[Address, float] = {}
        self.buckets: dict[Address, TokenBucket] = {}
        if remote is not None:
            self.buckets[remote] = TokenBucket(rate, burst)
        self.strangers = TokenBucket(rate, burst)
        self.targets: tuple[Address, ...] = (remote,) if remote else ()

    def allow(self, addr: Address) -> bool:
        """Whether a datagram from ``addr`` fits its bucket."""
        return self.buckets.get(addr, self.strangers).allow()

    def saw(self, addr: Address) -> None:
        now = time.monotonic()
        if addr == self.remote:
            return
        if addr in self.seen:
            self.seen[addr] = now
            return
        self.seen = {a: t for a, t in self.seen.items() if now - t < _PEER_TTL}
        self.buckets = {a: b for a, b in self.buckets.items() if a == self.remote or a in self.seen}
        if len(self.seen) < _MAX_PEERS:
            self.seen[addr] = now
            self.buckets[addr] = TokenBucket(self.rate, self.burst)
        self.targets = ((self.remote,) if self.remote else ()) + tuple(self.seen)


class UdpEndpoint(asyncio.DatagramProtocol):
    """One vehicle's UDP socket: sends first to ``remote``, answers whoever talks to it."""

    def __init__(
        self,
        node: VehicleNode,
        deliver: Deliver,
        remote: Address,
        flood_rate: float,
        sock: socket.socket,
    ) -> None:
        self.node = node
        self.deliver = deliver
        self.peers = PeerSet(remote, flood_rate, flood_rate / 4)
        self.decoder = FrameDecoder(node.stats)
        self.transport: asyncio.DatagramTransport | None = None
        self.sock: socket.socket | None = sock
        """Our own bound socket (also handed to the transport), for sending without a copy."""

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = cast(asyncio.DatagramTransport, transport)

    def connection_lost(self, exc: Exception | None) -> None:
        self.sock = None

    def datagram_received(self, data: bytes, addr: Address) -> None:
        if not self.peers.allow(addr):
            self.node.stats.flood_dropped += 1
            return
        msgs = self.node.authentic(self.decoder.feed(data))
        if msgs:  # only a sender of accepted messages becomes a peer
            self.peers.saw(addr)
            self.deliver(self.node, msgs)

    def error_received(self, exc: Exception) -> None:
        # ICMP port unreachable while no client listens yet: normal for a vehicle sending first.
        pass

    def send(self, data: bytes) -> None:
        if self.sock is None:
            return
        for addr in self.peers.targets:
            try:
                # The raw socket: the transport's wrapper costs more than the send itself,
                # and a full kernel buffer should drop telemetry, not queue it.
                self.sock.sendto(data, addr)
            except (BlockingIOError, InterruptedError):
                self.node.stats.tx_dropped += 1
            except OSError:
                pass  # no listener yet (ICMP unreachable): normal for a vehicle sending first


class TcpServer:
    """One vehicle's TCP server (ArduPilot SITL style); every client gets the full stream."""

    def __init__(self, node: VehicleNode, deliver: Deliver) -> None:
        self.node = node
        self.deliver = deliver
        self.server: asyncio.Server | None = None

    async def start(self, host: str, port: int) -> None:
        self.server = await asyncio.start_server(self._client, host, port)

    async def _client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        decoder = FrameDecoder(self.node.stats, stream=True)

        def send(data: bytes) -> None:
            if writer.is_closing():
                return
            if writer.transport.get_write_buffer_size() < _TCP_BACKLOG_LIMIT:
                writer.write(data)

        self.node.outputs.append(send)
        try:
            while data := await reader.read(4096):
                msgs = self.node.authentic(decoder.feed(data))
                if msgs:
                    self.deliver(self.node, msgs)
        except (ConnectionError, OSError):
            pass
        finally:
            self.node.outputs.remove(send)
            writer.close()

    def close(self) -> None:
        if self.server is not None:
            self.server.close()


class GcsEndpoint(asyncio.DatagramProtocol):
    """A ground-station output carrying all vehicles; replies are routed by target_system."""

    def __init__(self, nodes: list[VehicleNode], deliver: Deliver, remote: Address) -> None:
        self.nodes = nodes
        self.deliver = deliver
        self.peers = PeerSet(remote, 20000.0, 5000.0)
        self.stats = LinkStats()
        self.decoder = FrameDecoder(self.stats)
        self.transport: asyncio.DatagramTransport | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = cast(asyncio.DatagramTransport, transport)

    def datagram_received(self, data: bytes, addr: Address) -> None:
        if not self.peers.allow(addr):
            self.stats.flood_dropped += 1
            return
        msgs = self.decoder.feed(data)
        routed: list[tuple[VehicleNode, list[Any]]] = []
        for msg in msgs:
            target = getattr(msg, "target_system", 0)
            if target == 0:
                nodes = self.nodes
            elif 1 <= target <= len(self.nodes):
                nodes = [self.nodes[target - 1]]
            else:
                self.stats.not_for_us += 1
                continue
            routed += [(node, ok) for node in nodes if (ok := node.authentic([msg]))]
        # A sender becomes a peer by speaking MAVLink; with signing on, by an accepted message.
        if routed or (msgs and self.nodes[0].encoder.signing is None):
            self.peers.saw(addr)
        for node, accepted in routed:
            self.deliver(node, accepted)

    def error_received(self, exc: Exception) -> None:
        pass

    def send(self, data: bytes) -> None:
        if self.transport is None or self.transport.is_closing():
            return
        for addr in self.peers.targets:
            self.transport.sendto(data, addr)
