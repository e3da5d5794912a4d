"""Targets that left the area during a fleet run, and how T_S counts them.

Under ``mission.ts_rule: confirmed_or_gone`` a real target counts towards T_S at the earlier of
its first confirmation and its departure, as in the Monte-Carlo engine (``mdm_core.metrics.
time_to_all``). Departures are on the mission clock (the emulator's, on which the targets'
paths run from 0, take-off included); T_S counts from the team's search start, the earliest
vehicle's, so a departure counts at its time after that start (0 if the target left before).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from companion.telemetry.mission_log import read_log
from mdm_ground.errors import GroundError

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


class EmulatorLogError(GroundError, ValueError):
    """A record of the emulator's event log that does not say what its event needs."""


def emulator_departures(records: list[dict[str, Any]], m: int, path: Path) -> FloatArray:
    """(m,) each target's departure, mission clock s, from the emulator's ``target_gone``
    events (inf: none logged for that target); ``records`` are those of ``path``."""
    out = np.full(m, np.inf)
    for rec in records:
        if rec.get("event") != "target_gone":
            continue
        try:
            k, left = int(rec["target"]), float(rec["left_at"])
        except (KeyError, TypeError, ValueError) as exc:
            raise EmulatorLogError(f"{path}: target_gone record {rec}: {exc!r}") from exc
        if not (0 <= k < m and np.isfinite(left)):
            raise EmulatorLogError(
                f"{path}: target_gone of target {k} at {left}: the profile has targets "
                f"0..{m - 1} and a departure is a finite time"
            )
        out[k] = min(out[k], left)
    return out


def team_search_start(log_dir: Path, vehicles: int) -> float | None:
    """The earliest search start any vehicle logged, mission clock s (None: no search began)."""
    starts = [read_log(log_dir / f"mission-{i}.jsonl").search_start for i in range(vehicles)]
    known = [s for s in starts if s is not None]
    return min(known) if known else None


@dataclass(frozen=True)
class TsCount:
    """What T_S counted each real target at."""

    gone: FloatArray
    """(m,) each target's departure after the team's search start, s (inf: it did not leave,
    or T_S counts confirmations only); what T_S takes the minimum of with the confirmation."""
    confirmed: int
    """Real targets counted at their first confirmation."""
    departed: int
    """Real targets counted at their departure (it came before any confirmation)."""


def ts_count(
    first: FloatArray,
    departures: FloatArray,
    search_start: float | None,
    real: BoolArray,
    rule: str,
) -> TsCount:
    """How T_S counts each real target: ``first`` (m,) team first confirmations after the
    search start, ``departures`` (m,) on the mission clock, ``rule`` the profile's ts_rule."""
    gone = np.full(len(first), np.inf)
    if rule == "confirmed_or_gone" and search_start is not None:
        gone = np.maximum(departures - search_start, 0.0)
    by_departure = real & (gone < first)
    by_confirmation = real & ~by_departure & np.isfinite(first)
    return TsCount(gone, int(by_confirmation.sum()), int(by_departure.sum()))
