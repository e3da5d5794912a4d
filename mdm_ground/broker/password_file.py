"""A Mosquitto password file (``password_file``): ``user:hash`` lines as ``mosquitto_passwd``
writes them, read and checked here, and written for a run's own accounts.

Hashes: ``$7$ITERATIONS$SALT$HASH`` (Mosquitto 2: PBKDF2-HMAC-SHA512) and ``$6$SALT$HASH``
(Mosquitto 1.x: SHA-512 of the password then the salt), salt and hash in base64.
"""

from __future__ import annotations

import base64
import binascii
import hashlib
import hmac
import os
from pathlib import Path

from mdm_ground.errors import GroundError

ITERATIONS = 101
"""PBKDF2 rounds of a hash written here: mosquitto_passwd 2.0's own count (the passwords of a
run's accounts are 128-bit random strings, not words to guess)."""
_SALT_BYTES = 12


class PasswordFileError(GroundError, ValueError):
    """A password file that cannot be read or holds a line Mosquitto would not take."""


def hash_password(password: str, *, salt: bytes | None = None, iterations: int = ITERATIONS) -> str:
    """A ``$7$`` hash of ``password``, as mosquitto_passwd writes it."""
    salt = os.urandom(_SALT_BYTES) if salt is None else salt
    digest = hashlib.pbkdf2_hmac("sha512", password.encode(), salt, iterations)
    return f"$7${iterations}${_b64(salt)}${_b64(digest)}"


def verify(password: str, stored: str) -> bool:
    """Whether ``password`` is the one ``stored`` (a ``$7$`` or ``$6$`` hash) was made of; an
    unknown or damaged hash verifies nothing."""
    parts = stored.split("$")
    try:
        if len(parts) == 5 and parts[1] == "7" and parts[2].isdigit():
            salt, want = base64.b64decode(parts[3]), base64.b64decode(parts[4])
            got = hashlib.pbkdf2_hmac("sha512", password.encode(), salt, int(parts[2]))
        elif len(parts) == 4 and parts[1] == "6":
            salt, want = base64.b64decode(parts[2]), base64.b64decode(parts[3])
            got = hashlib.sha512(password.encode() + salt).digest()
        else:
            return False
    except (binascii.Error, ValueError):
        return False
    return hmac.compare_digest(got, want)


def read_passwords(path: Path) -> dict[str, str]:
    """User -> stored hash; PasswordFileError naming the line of a malformed one."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise PasswordFileError(f"password file {path}: {exc}") from None
    users: dict[str, str] = {}
    for number, raw in enumerate(lines, 1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        user, sep, stored = line.partition(":")
        if not sep or not user or not stored.startswith(("$7$", "$6$")):
            raise PasswordFileError(
                f"password file {path}, line {number}: expected USER:$7$... or USER:$6$... "
                "(as mosquitto_passwd writes)"
            )
        users[user] = stored
    return users


def write_passwords(path: Path, passwords: dict[str, str]) -> None:
    """A password file of ``passwords`` (user -> clear password), hashed, readable by its
    owner alone."""
    text = "".join(f"{user}:{hash_password(pw)}\n" for user, pw in passwords.items())
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w", encoding="utf-8") as f:
        f.write(text)


def _b64(data: bytes) -> str:
    return base64.b64encode(data).decode()
