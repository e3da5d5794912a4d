"""A Mosquitto ACL file (``acl_file``), read and applied as Mosquitto 2 applies it.

``user NAME`` starts a user's section; ``topic [read|write|readwrite|deny] TOPIC`` grants (or
denies) that user a topic filter, or the anonymous clients before any ``user`` line;
``pattern [ACCESS] TOPIC`` applies to every client with ``%u`` (user name) and ``%c`` (client
id) substituted. A topic is allowed when no deny entry matches it and a grant with the access
does; a pattern naming ``%u`` or ``%c`` does not apply to a client whose name or id holds
``+`` or ``#`` (Mosquitto's rule: a name cannot widen a pattern). Subscriptions are never refused: what a client may read is
checked on every message delivered to it, retained or not (what Mosquitto 2.0 does with this
project's ACL, measured: tests/ground/broker/test_same_rules_as_mosquitto.py).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntFlag
from pathlib import Path

from mdm_ground.errors import GroundError


class AclFileError(GroundError, ValueError):
    """An ACL file that cannot be read or has a line Mosquitto would refuse."""


class Access(IntFlag):
    """What a grant allows (Mosquitto's MOSQ_ACL_READ / MOSQ_ACL_WRITE); 0 is a deny entry."""

    DENY = 0
    READ = 1
    WRITE = 2


_ACCESS = {
    "read": Access.READ,
    "write": Access.WRITE,
    "readwrite": Access.READ | Access.WRITE,
    "deny": Access.DENY,
}


@dataclass(frozen=True)
class Grant:
    """One ``topic`` or ``pattern`` line."""

    filter: str
    access: Access


@dataclass(frozen=True)
class AclRules:
    """Every line of one ACL file."""

    anonymous: tuple[Grant, ...] = ()
    """``topic`` lines before the first ``user`` line: for clients without a user name."""
    users: dict[str, tuple[Grant, ...]] = field(default_factory=dict)
    patterns: tuple[Grant, ...] = ()

    def allows(self, user: str | None, client_id: str, topic: str, access: Access) -> bool:
        """Whether ``user`` (None: anonymous) connected as ``client_id`` may read or write
        ``topic``."""
        grants = [
            *(self.anonymous if user is None else self.users.get(user, ())),
            *(
                Grant(_fill(g.filter, user, client_id), g.access)
                for g in self.patterns
                if _fillable(g.filter, user, client_id)
            ),
        ]
        matching = [g for g in grants if topic_matches(g.filter, topic)]
        if any(g.access == Access.DENY for g in matching):
            return False
        return any(g.access & access for g in matching)


def _fillable(pattern: str, user: str | None, client_id: str) -> bool:
    """A name with a wildcard in it would widen the pattern: such a client gets none of it."""
    if "%u" in pattern and (user is None or any(c in user for c in "+#")):
        return False
    return "%c" not in pattern or not any(c in client_id for c in "+#")


def _fill(pattern: str, user: str | None, client_id: str) -> str:
    return pattern.replace("%u", user or "").replace("%c", client_id)


def read_acl(path: Path) -> AclRules:
    """The rules of the ACL file at ``path``; AclFileError naming the line."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise AclFileError(f"ACL file {path}: {exc}") from None
    anonymous: list[Grant] = []
    users: dict[str, list[Grant]] = {}
    patterns: list[Grant] = []
    section = anonymous
    for number, raw in enumerate(lines, 1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        where = f"ACL file {path}, line {number}"
        kind, _, rest = line.partition(" ")
        rest = rest.strip()
        if kind == "user":
            if not rest:
                raise AclFileError(f"{where}: 'user' without a name")
            section = users.setdefault(rest, [])
        elif kind in ("topic", "pattern"):
            word, _, topic = rest.partition(" ")
            access = _ACCESS.get(word)
            if access is None:  # no access word: readwrite, the whole rest is the topic
                access, topic = Access.READ | Access.WRITE, rest
            topic = topic.strip()
            if not topic:
                raise AclFileError(f"{where}: {kind!r} without a topic")
            (patterns if kind == "pattern" else section).append(Grant(topic, access))
        else:
            raise AclFileError(
                f"{where}: {kind!r}: expected 'user NAME', 'topic [ACCESS] TOPIC' or "
                "'pattern [ACCESS] TOPIC'"
            )
    return AclRules(tuple(anonymous), {u: tuple(g) for u, g in users.items()}, tuple(patterns))


def topic_matches(topic_filter: str, topic: str) -> bool:
    """MQTT 3.1.1 matching (section 4.7): ``+`` one level, a last ``#`` any levels (the parent
    too); a leading wildcard never matches a ``$`` topic."""
    if topic.startswith("$") and topic_filter.startswith(("+", "#")):
        return False
    want, have = topic_filter.split("/"), topic.split("/")
    for i, level in enumerate(want):
        if level == "#":
            return i == len(want) - 1
        if i >= len(have) or level not in ("+", have[i]):
            return False
    return len(want) == len(have)
