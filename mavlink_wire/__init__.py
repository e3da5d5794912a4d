"""The MAVLink 2 wire shared by the emulator and the companion: frames built and read
(:mod:`mavlink_wire.frames`), their checksum (:mod:`mavlink_wire.crc`), and message signing (the
key, :mod:`mavlink_wire.signing_key`, and the state, :mod:`mavlink_wire.signing_state`)."""

from mavlink_wire.errors import SigningError
from mavlink_wire.signing_key import (
    ENV_VAR,
    SigningKeyError,
    load_signing_key,
    passphrase_to_secret,
)
from mavlink_wire.signing_state import SigningState, Verdict

__all__ = [
    "ENV_VAR",
    "SigningError",
    "SigningKeyError",
    "SigningState",
    "Verdict",
    "load_signing_key",
    "passphrase_to_secret",
]
