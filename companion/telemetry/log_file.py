"""`companion run --log-file`: the companion's log lines also in a file of the run directory,
bounded (rotated at ``max_bytes``, ``backups`` old files kept) and safe on a full disk: a write
that fails is said once on stderr (the journal, under systemd) and the lines are dropped until a
write succeeds again; logging never raises into the flight."""

from __future__ import annotations

import logging
import sys
from logging.handlers import RotatingFileHandler
from pathlib import Path

MAX_BYTES = 5_000_000
"""Default size of one log file before it rotates."""
BACKUPS = 3
"""Default number of rotated files kept (companion.log.1 .. .3): 20 MB at most in all."""


class BoundedLogFile(RotatingFileHandler):
    """A rotating log file that drops lines, saying so once, while the disk refuses them."""

    def __init__(self, path: Path, *, max_bytes: int = MAX_BYTES, backups: int = BACKUPS) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        super().__init__(path, maxBytes=max_bytes, backupCount=backups, encoding="utf-8")
        self.dropped = 0
        """Lines not written since the last one that was."""

    def emit(self, record: logging.LogRecord) -> None:
        before = self.dropped
        super().emit(record)  # a failure ends in handleError
        if self.dropped == before and before:
            sys.stderr.write(
                f"companion: log file {self.baseFilename} written again; {before} line(s) lost\n"
            )
            self.dropped = 0

    def handleError(self, record: logging.LogRecord) -> None:  # noqa: N802 (logging's name)
        exc = sys.exc_info()[1]
        if not self.dropped:
            sys.stderr.write(
                f"companion: log file {self.baseFilename}: {exc}; its lines are dropped "
                "until it can be written (the journal still has them)\n"
            )
        self.dropped += 1


def add_log_file(path: Path, fmt: str) -> BoundedLogFile:
    """Send the root logger's lines to ``path`` too, formatted as ``fmt``."""
    handler = BoundedLogFile(path)
    handler.setFormatter(logging.Formatter(fmt))
    logging.getLogger().addHandler(handler)
    return handler
