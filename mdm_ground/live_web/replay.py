"""A finished run read back from its directory: the page's state at any mission time."""

from __future__ import annotations

import bisect
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from companion.telemetry.mission_log import read_records
from mdm_ground.fleet.scoring import EMULATOR_EVENTS
from mdm_ground.live_web.fleet_state import FleetState
from mdm_profiles import MissionProfile

_LOG_NAME = re.compile(r"mission-(\d+)\.jsonl")


@dataclass(frozen=True)
class _Record:
    t: float
    vehicle: int
    record: dict[str, Any]


class Replay:
    """Every mission-log record of a run directory (and the emulator's arming events), in
    time order; :meth:`state_at` replays them up to a mission time."""

    def __init__(self, run_dir: Path, profile: MissionProfile, *, show_targets: bool) -> None:
        self.profile = profile
        self.show_targets = show_targets
        found = (_LOG_NAME.fullmatch(p.name) for p in run_dir.glob("mission-*.jsonl"))
        self.vehicles = sorted(int(m.group(1)) for m in found if m is not None)
        if not self.vehicles:
            raise ValueError(f"{run_dir}: no mission-I.jsonl in it (not a run directory?)")
        records: list[_Record] = []
        for i in self.vehicles:
            for r in read_records(run_dir / f"mission-{i}.jsonl"):
                t = r.get("t")
                if isinstance(t, int | float) and not isinstance(t, bool):
                    records.append(_Record(float(t), i, r))
        for r in read_records(run_dir / EMULATOR_EVENTS):
            if r.get("event") in ("armed", "disarmed") and isinstance(r.get("t"), int | float):
                records.append(_Record(float(r["t"]), int(r["vehicle"]), r))
        records.sort(key=lambda r: r.t)  # stable: a vehicle's records stay in their order
        self._records = records
        self._times = [r.t for r in records]
        self.end = self._times[-1] if records else 0.0

    def state_at(self, t: float) -> FleetState:
        """The page's state after every record up to mission time ``t``; positions between
        two ``tick`` records interpolated."""
        state = FleetState(self.profile, show_targets=self.show_targets, stale_after=float("inf"))
        upto = bisect.bisect_right(self._times, t)
        for i in self.vehicles:
            state.vehicle(i)
        for r in self._records[:upto]:
            kind = r.record.get("event")
            if kind in ("armed", "disarmed"):
                state.on_armed(r.vehicle, kind == "armed", r.t)
            else:
                state.on_event(r.vehicle, r.record, None)
        for i in self.vehicles:
            self._interpolate(state, i, t, upto)
            state.vehicles[i].t = min(max(state.vehicles[i].t, t), self._last(i))
        return state

    def _last(self, vehicle: int) -> float:
        return max((r.t for r in self._records if r.vehicle == vehicle), default=0.0)

    def _interpolate(self, state: FleetState, vehicle: int, t: float, upto: int) -> None:
        before = next((r for r in reversed(self._records[:upto]) if _is_tick(r, vehicle)), None)
        after = next((r for r in self._records[upto:] if _is_tick(r, vehicle)), None)
        if before is None or after is None or after.t <= before.t:
            return
        f = (t - before.t) / (after.t - before.t)
        v = state.vehicles[vehicle]
        a, b = before.record, after.record
        v.move_to(
            a["north"] + f * (b["north"] - a["north"]), a["east"] + f * (b["east"] - a["east"])
        )
        v.alt = a["alt"] + f * (b["alt"] - a["alt"])


def _is_tick(r: _Record, vehicle: int) -> bool:
    rec = r.record
    return (
        r.vehicle == vehicle
        and rec.get("event") == "tick"
        and all(isinstance(rec.get(k), int | float) for k in ("north", "east", "alt"))
    )
