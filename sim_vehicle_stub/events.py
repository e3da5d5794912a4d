"""Ground truth and events as JSON lines, one object per line, flushed per line."""

from __future__ import annotations

import json
from pathlib import Path
from typing import IO, Any


class EventLog:
    """Append-only event log; a no-op when no path is given."""

    def __init__(self, path: str | Path | None) -> None:
        self._file: IO[str] | None = Path(path).open("a", encoding="utf-8") if path else None  # noqa: SIM115
        self.count = 0

    def write(self, t: float, event: str, **fields: Any) -> None:
        """Record ``event`` at sim time ``t`` (seconds) with extra fields."""
        self.count += 1
        if self._file is None:
            return
        record = {"t": round(t, 4), "event": event, **fields}
        self._file.write(json.dumps(record, separators=(",", ":")) + "\n")
        self._file.flush()

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None
