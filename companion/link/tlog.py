"""MAVLink telemetry log (.tlog): each message prefixed by its 8-byte big-endian wall time in µs.

That is the format MAVProxy, QGroundControl and pymavlink's mavlogfile read. A write that fails
(a full disk) is logged once and the log stops there: the flight goes on without it.
"""

from __future__ import annotations

import logging
import struct
import time
from pathlib import Path
from typing import BinaryIO

_STAMP = struct.Struct(">Q")
log = logging.getLogger(__name__)


class TelemetryLog:
    """Append-only .tlog writer; written every ``flush_every`` messages and on close (one
    write of the messages gathered in memory: two file writes per message were a tenth of a
    sped-up companion's CPU)."""

    def __init__(self, path: Path, *, flush_every: int = 200) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        self.path = path
        self._file: BinaryIO = path.open("ab")
        self.failed: OSError | None = None
        """The error that stopped the log (a full disk), else None."""
        self._flush_every = 2 * flush_every
        self._chunks: list[bytes] = []

    def write(self, message: bytes) -> None:
        """Log one packed MAVLink message."""
        chunks = self._chunks
        chunks.append(_STAMP.pack(int(time.time() * 1e6)))
        chunks.append(message)
        if len(chunks) >= self._flush_every:
            self._flush()

    def _flush(self) -> None:
        data = b"".join(self._chunks)
        self._chunks.clear()
        if self.failed is not None:
            return
        try:
            self._file.write(data)
            self._file.flush()
        except OSError as exc:
            self.failed = exc
            log.error(
                "telemetry log %s: %s; no more of the flight is written to it", self.path, exc
            )

    def close(self) -> None:
        if not self._file.closed:
            self._flush()
            try:
                self._file.close()
            except OSError as exc:  # the buffered rest could not be written either
                if self.failed is None:
                    log.error("telemetry log %s: %s", self.path, exc)
