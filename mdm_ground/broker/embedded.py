"""The embedded broker: amqtt on a socket of its own (127.0.0.1 and a free port by default),
applying a Mosquitto password file and ACL (:mod:`mdm_ground.broker.amqtt_plugins`); clients
reach it over TCP as they reach Mosquitto."""

from __future__ import annotations

import asyncio
import logging
from importlib import metadata, resources
from pathlib import Path
from typing import Any

from amqtt.adapters import StreamReaderAdapter, StreamWriterAdapter
from amqtt.broker import Broker
from amqtt.session import Session

from mdm_ground.broker.acl_file import Access, AclRules, read_acl, topic_matches
from mdm_ground.errors import GroundError

log = logging.getLogger(__name__)
PROJECT_ACL = Path(str(resources.files("mdm_ground.broker") / "mosquitto.acl"))
"""docker/mosquitto/acl, shipped with the package (tests/ground/broker: the same file)."""
_LISTENER = "default"


class EmbeddedBrokerError(GroundError, ValueError):
    """The embedded broker could not start (its port taken, its rules unreadable ...)."""


def server_name() -> str:
    """``amqtt X.Y.Z``: what the run directory and the page say served the team."""
    return f"amqtt {metadata.version('amqtt')}"


class _CheckedBroker(Broker):  # type: ignore[misc]
    """amqtt's broker, with the retained messages a subscription brings sent as Mosquitto
    sends them. amqtt 0.12.1 sends them without asking the topic plugins (Mosquitto checks the
    ACL's read as for any delivery), and on every connection it also sends the new client the
    retained messages of every other client's filters (tests/ground/broker: a duplicate, or a
    message the client never subscribed to): here only those of the client's own filters."""

    def __init__(self, config: dict[str, Any], rules: AclRules) -> None:
        super().__init__(config)
        self._rules = rules

    async def _publish_retained_messages_for_subscription(
        self, subscription: tuple[str, int], session: Session
    ) -> None:
        topic_filter, qos = subscription
        _, handler = self.sessions.get(session.client_id, (None, None))
        subscribed = self.subscriptions.get(topic_filter, [])
        if handler is None or all(s.client_id != session.client_id for s, _ in subscribed):
            return
        sends = [
            handler.mqtt_publish(m.topic, m.data, min(qos, m.qos or qos), retain=True)
            for topic, m in list(self.retained_messages.items())
            if topic_matches(topic_filter, topic)
            and self._rules.allows(session.username, session.client_id, topic, Access.READ)
        ]
        for failed in await asyncio.gather(*sends, return_exceptions=True):
            if isinstance(failed, BaseException):
                log.warning("a retained message to %s was not sent: %s", session.client_id, failed)


class EmbeddedBroker:
    """``async with EmbeddedBroker(...) as broker``: serving on ``broker.host:broker.port``
    until the block ends."""

    def __init__(self, host: str, port: int, *, password_file: Path, acl: Path = PROJECT_ACL):
        self.host = host
        self.port = port
        """The port asked for until started (0: a free one), then the bound one."""
        self._password_file = password_file
        self._acl = acl
        self._broker: _CheckedBroker | None = None
        self._server: asyncio.Server | None = None

    @property
    def address(self) -> str:
        return f"[{self.host}]:{self.port}" if ":" in self.host else f"{self.host}:{self.port}"

    async def __aenter__(self) -> EmbeddedBroker:
        rules = read_acl(self._acl)
        files = {"acl_file": str(self._acl), "password_file": str(self._password_file)}
        config = {
            "listeners": {_LISTENER: {"type": "external"}},
            "plugins": {
                "mdm_ground.broker.amqtt_plugins.PasswordFilePlugin": files,
                "mdm_ground.broker.amqtt_plugins.AclPlugin": files,
            },
        }
        for name in ("amqtt", "transitions"):  # a line per connection and state change
            logging.getLogger(name).setLevel(logging.WARNING)
        broker = _CheckedBroker(config, rules)
        await broker.start()
        try:
            self._server = await asyncio.start_server(self._connected, self.host, self.port)
        except OSError as exc:
            await broker.shutdown()
            raise EmbeddedBrokerError(
                f"embedded MQTT broker: cannot listen on {self.address}: {exc.strerror}"
            ) from None
        self._broker = broker
        self.port = int(self._server.sockets[0].getsockname()[1])
        log.info("embedded MQTT broker (%s) on %s", server_name(), self.address)
        return self

    async def _connected(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        assert self._broker is not None, "connections come only once started"
        await self._broker.external_connected(
            StreamReaderAdapter(reader), StreamWriterAdapter(writer), _LISTENER
        )

    async def __aexit__(self, *_: object) -> None:
        if self._server is not None:
            self._server.close()
        if self._broker is not None:
            await self._broker.shutdown()
        self._broker = self._server = None
