"""How many vehicles for this site: the planner's figures (``mdm-montecarlo plan``).

For every method and team size: the profile flown with that team, the mission duration set to
the endurance (minutes of search per pack), T_S capped at the profile's cap or twice the
endurance, whichever is longer. From the runs: the probability of confirming every real target
within the endurance (the share of runs whose T_S is at most the endurance, with its standard
error sqrt(p (1 - p) / runs)), the expected number of real targets confirmed by then (mean
T_nc), T_S's 10/50/90 % quantiles, and per method the smallest team whose probability reaches
the one asked for.

Refused before any run (ValueError, exit 2 from the CLI): a profile without a site fence, an
endurance below the transit (the time to fly the search area's diagonal at the fleet speed:
below it a vehicle cannot reach the far side of the area from its start point), a team larger
than the profile can start (its altitude layers, fleet.altitude + (n - 1) x
fleet.altitude_step, above site.max_altitude: mdm_profiles.ceiling, as the companion checks
before it arms; or more vehicles than MAVLink system ids, 255).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mdm_montecarlo.engines.runner import MissionResults
from mdm_montecarlo.study.variants import with_fleet_size, with_method
from mdm_profiles import MissionProfile
from mdm_profiles.ceiling import CeilingError, check_ceiling

MAX_SYSTEM_IDS = 255


@dataclass(frozen=True)
class PlanAsk:
    profile: MissionProfile
    teams: tuple[int, ...]
    endurance_min: float
    methods: tuple[str, ...]
    want: float


@dataclass(frozen=True)
class PlanRow:
    method: str
    vehicles: int
    p_all: float
    p_all_se: float
    expected: float
    ts_q10: float
    ts_q50: float
    ts_q90: float
    runs: int


def transit_seconds(profile: MissionProfile) -> float:
    """Time to fly the search area's diagonal at the fleet speed."""
    return math.hypot(profile.area.north, profile.area.east) / profile.fleet.speed


def check(ask: PlanAsk) -> None:
    """Refuse what cannot be planned, naming what and why."""
    profile = ask.profile
    if profile.site is None:
        raise ValueError(
            f"profile {profile.name!r} has no site fence (site.geofence): plan is for a field "
            "site; import one from a QGroundControl .plan, KML or GeoJSON file with "
            "`companion profile import`"
        )
    if not ask.teams or min(ask.teams) < 1:
        raise ValueError(f"--teams {list(ask.teams)}: team sizes must be >= 1")
    if not 0.0 < ask.want < 1.0:
        raise ValueError(f"--want {ask.want}: a probability between 0 and 1 (exclusive)")
    transit = transit_seconds(profile)
    if ask.endurance_min * 60.0 < transit:
        raise ValueError(
            f"--endurance {ask.endurance_min:g} min is below the transit: the area's diagonal "
            f"({math.hypot(profile.area.north, profile.area.east):.0f} m) takes "
            f"{transit / 60:.1f} min at {profile.fleet.speed:g} m/s"
        )
    biggest = max(ask.teams)
    try:
        check_ceiling(profile, biggest)
    except CeilingError as exc:
        raise ValueError(
            f"--teams: {biggest} vehicles is more than profile {profile.name!r} can start: {exc}"
        ) from None
    if biggest > MAX_SYSTEM_IDS:
        raise ValueError(
            f"--teams: {biggest} vehicles; MAVLink system ids allow {MAX_SYSTEM_IDS} at most"
        )
    for method in ask.methods:
        with_method(profile, method)  # an unknown method: its ValueError


def profiles(ask: PlanAsk) -> list[tuple[str, int, MissionProfile]]:
    """(method, team size, profile) of every configuration, method by method."""
    duration = ask.endurance_min * 60.0
    out = []
    for method in ask.methods:
        for n in sorted(set(ask.teams)):
            p = with_fleet_size(with_method(ask.profile, method), n)
            cap = max(p.mission.ts_cap, 2.0 * duration)
            mission = p.mission.model_copy(update={"duration": duration, "ts_cap": cap})
            out.append((method, n, p.model_copy(update={"mission": mission})))
    return out


def plan_row(method: str, vehicles: int, result: MissionResults) -> PlanRow:
    ts, _ = result.ts()
    within = ts <= result.profile.mission.duration
    p = float(within.mean())
    real = result.real
    expected = (result.team_times[:, real] <= result.profile.mission.duration).sum(axis=1)
    q = np.quantile(ts, [0.1, 0.5, 0.9])
    return PlanRow(
        method,
        vehicles,
        p,
        math.sqrt(p * (1.0 - p) / len(ts)),
        float(expected.mean()),
        float(q[0]),
        float(q[1]),
        float(q[2]),
        len(ts),
    )


def smallest_teams(rows: list[PlanRow], want: float) -> dict[str, int | None]:
    """Per method, the smallest team whose probability reaches ``want`` (None: none does)."""
    out: dict[str, int | None] = {}
    for row in sorted(rows, key=lambda r: r.vehicles):
        out.setdefault(row.method, None)
        if out[row.method] is None and row.p_all >= want:
            out[row.method] = row.vehicles
    return out


def format_plan(rows: list[PlanRow], ask: PlanAsk) -> str:
    cap = max(ask.profile.mission.ts_cap, 2 * ask.endurance_min * 60)
    lines = [
        f"Site {ask.profile.name!r}, endurance {ask.endurance_min:g} min of search per pack, "
        f"{rows[0].runs if rows else 0} runs per row; T_S quantiles in min "
        f"(>{cap / 60:g}: not all confirmed by the cap)",
        "",
        "| method | vehicles | P(all real confirmed) | ± s.e. | expected confirmed | "
        "T_S 10 % | T_S 50 % | T_S 90 % |",
        "|---|---|---|---|---|---|---|---|",
    ]

    def minutes(s: float) -> str:
        return f">{cap / 60:g}" if s >= cap else f"{s / 60:.1f}"

    for r in rows:
        lines.append(
            f"| {r.method} | {r.vehicles} | {r.p_all:.3f} | {r.p_all_se:.3f} | "
            f"{r.expected:.2f} | {minutes(r.ts_q10)} | {minutes(r.ts_q50)} | "
            f"{minutes(r.ts_q90)} |"
        )
    lines.append("")
    for method, n in smallest_teams(rows, ask.want).items():
        reach = f"{n} vehicles" if n is not None else "no team size asked"
        lines.append(f"- {method}: smallest team with P >= {ask.want:g}: {reach}")
    return "\n".join(lines)
