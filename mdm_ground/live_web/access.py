"""Who may command: loopback binds are open, any other bind needs the token."""

from __future__ import annotations

import hmac
import ipaddress
import os
import secrets
from dataclasses import dataclass
from pathlib import Path

from mdm_ground.errors import GroundError

TOKEN_ENV = "MDM_WEB_TOKEN"


class AccessError(GroundError):
    """A request the page refuses; ``status`` is the HTTP status to answer with."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


def is_loopback(host: str) -> bool:
    """127.0.0.0/8, ::1 and ``localhost``: only this machine can reach the page."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False  # a host name: it may resolve to anything


@dataclass(frozen=True)
class Access:
    """What the page lets a client do."""

    read_only: bool
    token: str | None
    """Required on every command when set."""

    def check_command(self, given: str | None) -> None:
        """Raise AccessError unless a command with ``given`` as its token may be sent."""
        if self.read_only:
            raise AccessError(403, "this page is read-only (--web-read-only): no commands")
        if self.token is None:
            return
        if not given:
            raise AccessError(
                401,
                "a token is required for commands on this bind address "
                "(the one printed at start, --web-token-file or $MDM_WEB_TOKEN)",
            )
        if not hmac.compare_digest(given.encode(), self.token.encode()):
            raise AccessError(401, "wrong token")


def resolve_access(host: str, *, read_only: bool, token_file: Path | None) -> tuple[Access, bool]:
    """The access rules for a bind to ``host``, and whether the token was generated here (to
    be printed). A token file or $MDM_WEB_TOKEN applies on any bind; without either, a
    non-loopback bind gets a fresh random token."""
    token: str | None = None
    if token_file is not None:
        try:
            lines = token_file.read_text(encoding="utf-8").splitlines()
        except OSError as exc:
            raise ValueError(f"--web-token-file {token_file}: {exc.strerror}") from None
        token = lines[0].strip() if lines else ""
        if len(token) < 16:
            raise ValueError(
                f"--web-token-file {token_file}: the first line must hold a token "
                "of at least 16 characters"
            )
    elif os.environ.get(TOKEN_ENV):
        token = os.environ[TOKEN_ENV]
        if len(token) < 16:
            raise ValueError(f"${TOKEN_ENV}: a token of at least 16 characters")
    if token is not None or read_only or is_loopback(host):
        return Access(read_only, token), False
    return Access(read_only, secrets.token_urlsafe(24)), True
