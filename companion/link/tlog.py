"""MAVLink telemetry log (.tlog): each message prefixed by its 8-byte big-endian wall time in µs.

That is the format MAVProxy, QGroundControl and pymavlink's mavlogfile read.
"""

from __future__ import annotations

import struct
import time
from pathlib import Path
from typing import BinaryIO


class TelemetryLog:
    """Append-only .tlog writer; flushed every ``flush_every`` messages and on close."""

    def __init__(self, path: Path, *, flush_every: int = 200) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        self._file: BinaryIO = path.open("ab")
        self._flush_every = flush_every
        self._pending = 0

    def write(self, message: bytes) -> None:
        """Log one packed MAVLink message."""
        self._file.write(struct.pack(">Q", int(time.time() * 1e6)) + message)
        self._pending += 1
        if self._pending >= self._flush_every:
            self._file.flush()
            self._pending = 0

    def close(self) -> None:
        if not self._file.closed:
            self._file.flush()
            self._file.close()
