"""The links' error: raised where a link cannot be opened or a command not delivered."""

from __future__ import annotations

from companion.errors import CompanionError


class LinkError(CompanionError, RuntimeError):
    """The link cannot be opened or a command could not be delivered."""
