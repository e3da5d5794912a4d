"""After a fleet run, from each vehicle's mission log (the positions its autopilot reported,
one ``tick`` every 10 vehicle s): did it search in its own altitude layer (Assumption III, the
only separation of a team that does not talk), and how much of its search time was spent near
the fence (docs/model.md, "Search near the fence")."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from companion.fence_from_profile import fence_for
from companion.mission.layer_watch import LAYER_TOLERANCE_M
from companion.mission.phase import Phase
from companion.telemetry.mission_log import read_records
from mdm_profiles import MissionProfile

NEAR_FENCE_M = 30.0
"""A search sample this close to the fence line (the site's fence, else the area's edge) counts
as "near the fence"."""


@dataclass(frozen=True)
class FlightCheck:
    """One vehicle's search as its mission log has it."""

    vehicle: int
    layer: float
    """The altitude it was to search at, m above home."""
    samples: int
    """Search ticks read."""
    outside_layer: int
    """Search ticks more than LAYER_TOLERANCE_M from ``layer``."""
    worst_altitude: float | None
    """The altitude of the search tick farthest from ``layer``."""
    near_fence: float | None
    """Share of search ticks within NEAR_FENCE_M of the fence, 0..1 (None: no search ticks)."""

    def problem(self) -> str | None:
        """A line for the summary when the vehicle left its layer."""
        if not self.outside_layer:
            return None
        return (
            f"vehicle {self.vehicle} left its altitude layer {self.layer:g} m: "
            f"{self.outside_layer} of {self.samples} search samples more than "
            f"{LAYER_TOLERANCE_M:g} m off (worst {self.worst_altitude} m)"
        )


def flight_checks(profile: MissionProfile, out: Path, vehicles: int) -> list[FlightCheck]:
    """The check of every vehicle of a run in ``out``."""
    fence = fence_for(profile)
    fleet = profile.fleet
    checks = []
    for i in range(vehicles):
        layer = fleet.altitude + i * fleet.altitude_step
        search = [
            r
            for r in read_records(out / f"mission-{i}.jsonl")
            if r.get("event") == "tick"
            and r.get("phase") == Phase.SEARCH.value
            and all(isinstance(r.get(k), int | float) for k in ("north", "east", "alt"))
        ]
        off = [float(r["alt"]) for r in search if abs(float(r["alt"]) - layer) > LAYER_TOLERANCE_M]
        worst = max(search, key=lambda r: abs(float(r["alt"]) - layer), default=None)
        near = sum(
            fence.distance(float(r["north"]), float(r["east"])) <= NEAR_FENCE_M for r in search
        )
        checks.append(
            FlightCheck(
                vehicle=i,
                layer=layer,
                samples=len(search),
                outside_layer=len(off),
                worst_altitude=None if worst is None else float(worst["alt"]),
                near_fence=near / len(search) if search else None,
            )
        )
    return checks
