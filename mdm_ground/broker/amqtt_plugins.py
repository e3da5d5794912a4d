"""The Mosquitto rules as amqtt plugins: the password file (no anonymous client), the ACL on
every publish and every delivery, and the ACL on a client's last will, which amqtt would
otherwise publish unchecked (Mosquitto drops a will its client may not write)."""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

from amqtt.contexts import Action, BaseContext
from amqtt.plugins.base import BaseAuthPlugin, BaseTopicPlugin
from amqtt.session import Session

from mdm_ground.broker.acl_file import Access, read_acl
from mdm_ground.broker.password_file import read_passwords, verify

log = logging.getLogger(__name__)


@dataclass
class RulesConfig:
    """Where the rules are (amqtt hands each plugin this, filled from the broker's config)."""

    acl_file: str
    password_file: str


class PasswordFilePlugin(BaseAuthPlugin):  # type: ignore[misc]
    """A client connects with a user name and its password from the password file, or not at
    all; a will on a topic the client may not write is dropped."""

    Config = RulesConfig

    def __init__(self, context: BaseContext) -> None:
        super().__init__(context)
        self._passwords = read_passwords(Path(self.config.password_file))
        self._rules = read_acl(Path(self.config.acl_file))

    async def authenticate(self, *, session: Session) -> bool:
        user = session.username
        stored = None if user is None else self._passwords.get(user)
        if stored is None or not verify(session.password or "", stored):
            log.info("MQTT client %s (user %r) refused: not authorised", session.client_id, user)
            return False
        topic = session.will_topic
        if session.will_flag and (
            topic is None or not self._rules.allows(user, session.client_id, topic, Access.WRITE)
        ):
            log.warning("MQTT client %s (user %s): its will on %s is not allowed: dropped",
                        session.client_id, user, topic)  # fmt: skip
            session.will_flag = False
        return True


class AclPlugin(BaseTopicPlugin):  # type: ignore[misc]
    """Publish: the ACL's write; delivery (live or retained): its read; subscribe: always (the
    deliveries are checked, as Mosquitto 2 does)."""

    Config = RulesConfig

    def __init__(self, context: BaseContext) -> None:
        super().__init__(context)
        self._rules = read_acl(Path(self.config.acl_file))

    async def topic_filtering(
        self,
        *,
        session: Session | None = None,
        topic: str | None = None,
        action: Action | None = None,
    ) -> bool:
        if action == Action.SUBSCRIBE:
            return True
        if session is None or topic is None:
            return False
        access = Access.WRITE if action == Action.PUBLISH else Access.READ
        return self._rules.allows(session.username, session.client_id or "", topic, access)
