"""MAVLink 2 message signing shared by the emulator and the companion: the key and the state
(and the frame checksum, `mavlink_signing.frame_crc`)."""

from mavlink_signing.errors import SigningError
from mavlink_signing.key import ENV_VAR, SigningKeyError, load_signing_key, passphrase_to_secret
from mavlink_signing.state import SigningState, Verdict

__all__ = [
    "ENV_VAR",
    "SigningError",
    "SigningKeyError",
    "SigningState",
    "Verdict",
    "load_signing_key",
    "passphrase_to_secret",
]
