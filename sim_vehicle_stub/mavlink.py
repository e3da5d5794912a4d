"""The MAVLink 2 dialect the emulator speaks (ardupilotmega, which includes common)."""

from __future__ import annotations

import os

os.environ.setdefault("MAVLINK20", "1")

from pymavlink.dialects.v20 import ardupilotmega as dialect

__all__ = ["dialect"]
