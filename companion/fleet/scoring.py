"""Score a fleet run from the companions' mission logs against the profile's targets."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from companion.telemetry.mission_log import read_records
from mdm_montecarlo.metrics import confirmed_within, team_times, time_to_all
from mdm_profiles import MissionProfile


@dataclass
class Confirmation:
    """One confirmation a companion logged, matched to the nearest profile target."""

    vehicle: int
    time: float
    """Seconds after that vehicle's search started."""
    north: float
    east: float
    target: int
    """Index of the nearest target in the profile."""
    distance: float
    real: bool
    """The nearest target is real and within the confirmation radius."""


@dataclass
class FleetResult:
    """What a fleet run found, with the Monte-Carlo engine's metrics."""

    profile: str
    vehicles: int
    duration: float
    tnc: int
    """Distinct real targets confirmed within ``duration`` (T_nc)."""
    ts: float
    """Time to confirm every real target (capped at the profile's ts_cap)."""
    ts_capped: bool
    first_confirmation: list[float]
    """Per target, the team's first confirmation time (inf: never)."""
    false_confirmations: int
    confirmations: list[Confirmation] = field(default_factory=list)
    end_reasons: dict[int, str] = field(default_factory=dict)

    def as_json(self) -> dict[str, Any]:
        out = asdict(self)
        out["first_confirmation"] = [
            None if not np.isfinite(t) else t for t in self.first_confirmation
        ]
        return out


def score(profile: MissionProfile, log_dir: Path, vehicles: int, duration: float) -> FleetResult:
    """Read mission-<i>.jsonl of every vehicle and compute T_nc, T_S and the false confirmations."""
    targets = np.array([[t.north, t.east] for t in profile.targets])
    real = np.array([not t.false_target for t in profile.targets])
    radius = profile.sensors[-1].radius
    per_vehicle = np.full((1, vehicles, len(targets)), np.inf)
    found: list[Confirmation] = []
    reasons: dict[int, str] = {}
    for i in range(vehicles):
        start: float | None = None
        for rec in read_records(log_dir / f"mission-{i}.jsonl"):
            if rec.get("event") == "phase" and "search_start" in rec and start is None:
                start = float(rec["search_start"])
            elif rec.get("event") == "end":
                reasons[i] = str(rec.get("reason"))
            elif rec.get("event") == "confirmation":
                where = np.array([rec["north"], rec["east"]], dtype=float)
                gaps = np.linalg.norm(targets - where, axis=1)
                k = int(np.argmin(gaps))
                t = float(rec["t"]) - (start or 0.0)
                ok = bool(real[k] and gaps[k] <= radius)
                found.append(
                    Confirmation(i, t, float(where[0]), float(where[1]), k, float(gaps[k]), ok)
                )
                if ok:
                    per_vehicle[0, i, k] = min(per_vehicle[0, i, k], t)
    times = team_times(per_vehicle)
    tnc = int(confirmed_within(times, duration)[0])
    ts, capped = time_to_all(times, real, profile.mission.ts_cap)
    return FleetResult(
        profile=profile.name,
        vehicles=vehicles,
        duration=duration,
        tnc=tnc,
        ts=float(ts[0]),
        ts_capped=bool(capped[0]),
        first_confirmation=[float(x) for x in times[0]],
        false_confirmations=sum(not c.real for c in found),
        confirmations=found,
        end_reasons=reasons,
    )
