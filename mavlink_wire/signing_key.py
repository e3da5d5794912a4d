"""Where the MAVLink 2 signing secret comes from: a key file or the environment, never a profile.

The file (or the variable) holds a passphrase; the 32-byte secret is its SHA-256, as MAVProxy's
``signing setup PASSPHRASE`` / ``signing key PASSPHRASE`` derive it, so MAVProxy can join a
signed link with the same passphrase.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Mapping
from pathlib import Path

from mavlink_wire.errors import SigningError

ENV_VAR = "MDM_MAVLINK_KEY"
"""Environment variable holding the passphrase; unset or empty means signing off."""
MIN_PASSPHRASE = 8


class SigningKeyError(SigningError, ValueError):
    """A key file or variable that is missing, unreadable or malformed; names what and where."""


def passphrase_to_secret(passphrase: str) -> bytes:
    """The 32-byte secret of a passphrase: SHA-256 of its ASCII bytes (MAVProxy's rule)."""
    return hashlib.sha256(passphrase.encode("ascii")).digest()


def _parse(text: str, where: str) -> bytes:
    passphrase = text.strip()
    if not passphrase:
        raise SigningKeyError(f"{where}: empty; expected one passphrase")
    if any(c.isspace() for c in passphrase):
        raise SigningKeyError(f"{where}: the passphrase must be one word without whitespace")
    if not all(33 <= ord(c) < 127 for c in passphrase):
        raise SigningKeyError(f"{where}: the passphrase must be printable ASCII")
    if len(passphrase) < MIN_PASSPHRASE:
        raise SigningKeyError(
            f"{where}: passphrase of {len(passphrase)} characters; at least {MIN_PASSPHRASE}"
        )
    return passphrase_to_secret(passphrase)


def load_signing_key(path: Path | None, environ: Mapping[str, str] | None = None) -> bytes | None:
    """The secret from ``path`` if given, else from $MDM_MAVLINK_KEY; None when neither is set."""
    if path is not None:
        try:
            text = path.read_text(encoding="ascii")
        except UnicodeDecodeError:
            raise SigningKeyError(f"signing key file {path}: not ASCII text") from None
        except OSError as exc:
            raise SigningKeyError(f"signing key file {path}: {exc.strerror or exc}") from None
        return _parse(text, f"signing key file {path}")
    value = (os.environ if environ is None else environ).get(ENV_VAR, "")
    if not value:
        return None
    return _parse(value, f"environment variable {ENV_VAR}")
