"""The mission profile schema (pydantic). Lengths in metres, times in seconds, frames (north, east)."""

from __future__ import annotations

from itertools import pairwise
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from mdm_profiles.failsafe import FailsafeSpec
from mdm_profiles.lawnmower_spec import LawnmowerSpec
from mdm_profiles.mqtt_spec import MqttSpec
from mdm_profiles.sensor_source import SensorSourceSpec
from mdm_profiles.swarm import SwarmSpec

MAX_SPEED = 300.0
"""m/s: faster than any UAV this search is for; a vehicle at 1e9 m/s would fly legs of
microseconds and a mission would take forever to simulate."""
MAX_MISSION_TIME = 1_000_000.0
"""s (11.6 days): longest mission duration and T_S cap; the engine simulates up to them."""
MIN_STEP = 1.0
"""m: shortest step length delta_k."""
MAX_LEGS = 100_000
"""Most legs (or swarm iterations) one vehicle may need to reach mission.ts_cap: more is a
simulation that effectively never ends."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Area(_Strict):
    north: float = Field(gt=0, description="Extent along north (the paper's L), m.")
    east: float = Field(gt=0, description="Extent along east (the paper's W), m.")


class Origin(_Strict):
    """WGS84 position of the area's (0, 0) corner; only the link layer converts with it."""

    lat: float = Field(ge=-90, le=90)
    lon: float = Field(ge=-180, le=180)
    alt: float = Field(default=0.0, description="Altitude AMSL of the origin, m.")


class TargetEntry(_Strict):
    north: float
    east: float
    appear: float = Field(default=0.0, ge=0, description="Time the target appears, s.")
    false_target: bool = Field(
        default=False, description="A false target: detection fires, never confirmation."
    )


class RandomWalkSpec(_Strict):
    """Dynamic targets: X(k+1) = X(k) + R(low, high) * speed * sample_time (eq. 2)."""

    speed: float = Field(default=5.0, gt=0, le=MAX_SPEED)
    low: float = -0.2
    high: float = 1.0
    sample_time: float = Field(default=0.1, gt=0)
    shared_axes: bool = False
    boundary: Literal["reflect", "clamp", "bounce", "free"] = "reflect"
    grid_dt: float = Field(
        default=10.0, gt=0, description="Node spacing of stored target paths, s."
    )

    @model_validator(mode="after")
    def _bounds(self) -> RandomWalkSpec:
        if not self.high > self.low:
            raise ValueError(f"high ({self.high}) must be greater than low ({self.low})")
        return self


class SensorSpec(_Strict):
    name: str
    radius: float = Field(gt=0, description="Sensing radius r_k, m.")


class FleetSpec(_Strict):
    vehicles: int = Field(default=12, ge=1, le=1000)
    speed: float = Field(
        default=20.0, gt=0, le=MAX_SPEED, description=f"||V_U||, m/s (at most {MAX_SPEED:g})."
    )
    tau: float = Field(default=0.33, gt=0, description="Velocity-loop time constant, s.")
    start: Literal["periphery_random", "periphery_even"] = "periphery_random"
    altitude: float = Field(default=30.0, gt=0, description="Altitude of vehicle 1 above home, m.")
    altitude_step: float = Field(
        default=5.0, ge=0, description="Vertical separation, m (Assumption III)."
    )
    acceptance_radius: float = Field(
        default=5.0, gt=0, description="A waypoint counts as reached within this, m."
    )


class DecayIndexSpec(_Strict):
    gamma: float = 0.1
    index_max: float = 0.95
    index_min: float = 0.2
    kappa: float = Field(default=150.0, gt=0)
    start: Literal["printed", "max"] = Field(
        default="printed",
        description="printed: C_I = gamma + (max - min) e^(-t/kappa) (starts at gamma + max - "
        "min); max: gamma + (max - gamma) e^(-t/kappa), starting at C_Imax as the text says.",
    )

    @model_validator(mode="after")
    def _order(self) -> DecayIndexSpec:
        if not 0 < self.gamma < self.index_min < self.index_max:
            raise ValueError("needs 0 < gamma < index_min < index_max")
        if self.gamma + self.index_max - self.index_min <= self.index_min:
            raise ValueError("gamma + index_max - index_min must exceed index_min")
        return self


class LevelSpec(_Strict):
    distribution: Literal["LS", "BS", "US"]
    step: float = Field(ge=MIN_STEP, description=f"Step length delta_k, m (at least {MIN_STEP:g}).")
    index: DecayIndexSpec | None = Field(default=None, description="C_I / D_I; levels >= 2 only.")
    step_law: Literal["fixed", "levy"] = "fixed"


class DistributionParams(_Strict):
    levy_index: float = Field(default=1.0, gt=0, le=2, description="LS lambda.")
    levy_scale: float = Field(default=1.0, gt=0, description="LS alpha.")
    brownian_sigma: float = Field(default=1.0, gt=0, description="BS sigma.")
    uniform_low: float = Field(default=-1.0, description="US v_l.")
    uniform_high: float = Field(default=1.0, description="US v_u.")

    @model_validator(mode="after")
    def _uniform(self) -> DistributionParams:
        if not self.uniform_high > self.uniform_low:
            raise ValueError("uniform_high must be greater than uniform_low")
        return self


class PolicySpec(_Strict):
    kind: Literal["mdm", "sss", "pso", "spso", "arpso", "lm1", "lm2"] = "mdm"
    levels: list[LevelSpec] = Field(min_length=1)
    distributions: DistributionParams = DistributionParams()
    out_of_area: Literal["reflect", "clip", "redraw"] = "reflect"
    waypoint_origin: Literal["position", "anchor"] = "position"
    confine_to_detection: bool = True
    anchor_at: Literal["vehicle", "target"] = Field(
        default="vehicle",
        description="Where a detection puts the anchor (the centre of the next level's disc "
        "and its waypoints' origin): the vehicle's position at the detection, or the detected "
        "target's position then (a detection sensor that locates; docs/model.md, 'What motion "
        "costs MDM').",
    )
    redetection: Literal["ignore", "recentre", "renew"] = Field(
        default="ignore",
        description="The detection sensor read on the last level too, when the vehicle "
        "reaches a waypoint or its index runs out: ignore = the last level listens to the "
        "confirmation sensor alone; recentre = a detection there moves the anchor as anchor_at "
        "says; renew = recentre and the level's decaying index starts again (engine only; "
        "docs/model.md, 'What motion costs MDM').",
    )
    memory_radius: float = Field(default=400.0, ge=0)
    detection_memory: Literal["disc", "exact", "none"] = Field(
        default="disc",
        description="Detections near targets this vehicle confirmed: disc = ignored while one "
        "lies within the detection radius of the vehicle; none = never ignored; exact = the "
        "contacted target's true position within memory_radius of one (docs/model.md).",
    )
    fallback_blind_time: float = Field(
        default=0.0,
        ge=0,
        le=3600,
        description="After the decaying index ends a level, level 1 ignores detections this "
        "long, s (0 to 3600; 0 = re-detect at once).",
    )
    swarm: SwarmSpec = Field(
        default=SwarmSpec(), description="PSO/SPSO/ARPSO parameters; levels[0] explores."
    )
    lawnmower: LawnmowerSpec = Field(
        default=LawnmowerSpec(), description="lm1/lm2 (partitioned lawnmower) parameters."
    )


class MissionSpec(_Strict):
    duration: float = Field(
        default=1000.0,
        gt=0,
        le=MAX_MISSION_TIME,
        description=f"Fixed duration for T_nc, s (at most {MAX_MISSION_TIME:g}).",
    )
    ts_cap: float = Field(
        default=40000.0,
        gt=0,
        le=MAX_MISSION_TIME,
        description=f"T_S of runs that never finish, s (at most {MAX_MISSION_TIME:g}).",
    )
    ts_rule: Literal["confirmed", "confirmed_or_gone"] = Field(
        default="confirmed",
        description="T_S: the time every real target is confirmed (confirmed), or confirmed "
        "or gone out of the area, whichever is first (confirmed_or_gone; with "
        "target_motion.boundary free).",
    )


class GeoPoint(_Strict):
    lat: float = Field(ge=-90, le=90)
    lon: float = Field(ge=-180, le=180)


DEFAULT_MAX_ALTITUDE = 120.0
"""The ceiling, m above the take-off point, where a profile sets none (the usual legal limit)."""


class SiteSpec(_Strict):
    """A real flying site (field profiles): geofence, link and failsafe choices of the companion."""

    name: str = ""
    geofence: list[GeoPoint] = Field(
        min_length=3, description="Polygon (WGS84) every commanded point stays inside."
    )
    connect: str | None = Field(
        default=None,
        description="Link URL of vehicle 0; '{port}' is replaced by base port + vehicle index.",
    )
    end_action: Literal["rtl", "land"] = "rtl"
    battery_min: float = Field(default=25.0, ge=0, le=100, description="End below this, %.")
    battery_reserve: float | None = Field(
        default=10.0,
        ge=0,
        le=100,
        description="Also end when what is left is what the flight home needs, at the drain "
        "measured so far in this flight, plus this reserve, %; null: battery_min only.",
    )
    return_speed: float | None = Field(
        default=None,
        gt=0,
        le=100,
        description="The end action's speed toward home (m/s) the reserve rule counts with; "
        "None: fleet.speed (ArduCopter's RTL at WPNAV_SPEED, which the companion sets to it; "
        "PX4 returns at MPC_XY_CRUISE, stock 5 m/s: set it here).",
    )
    descent_speed: float = Field(
        default=1.0,
        gt=0,
        le=20,
        description="The end action's descent speed to the ground (m/s) the reserve rule "
        "counts with.",
    )
    start_margin: float = Field(
        default=100.0,
        ge=0,
        le=1e5,
        description="The companion refuses to start a vehicle farther than this (m) outside "
        "the search area.",
    )
    max_altitude: float = Field(
        default=DEFAULT_MAX_ALTITUDE,
        gt=0,
        le=1e4,
        description="The ceiling, m above the take-off point: every vehicle's layer "
        "(fleet.altitude + i x fleet.altitude_step) stays under it.",
    )
    fence_inset: float = Field(
        default=20.0,
        ge=0,
        le=1e4,
        description="Commanded points stay this far (m) inside the geofence: room for the "
        "vehicle to brake without crossing it.",
    )


class MissionProfile(_Strict):
    """A whole mission: world, fleet, sensors, policy and timing."""

    name: str
    description: str = ""
    area: Area
    origin: Origin = Origin(lat=47.397742, lon=8.545594, alt=488.0)
    targets: list[TargetEntry] = Field(min_length=1)
    target_motion: RandomWalkSpec | None = None
    fleet: FleetSpec = FleetSpec()
    sensors: list[SensorSpec] = Field(
        min_length=1, description="Detection sensors, then confirmation."
    )
    sensor_source: SensorSourceSpec = Field(
        default=SensorSourceSpec(), description="Where the companion's readings come from."
    )
    policy: PolicySpec
    mission: MissionSpec = MissionSpec()
    site: SiteSpec | None = Field(default=None, description="Field profiles only.")
    mqtt: MqttSpec | None = Field(default=None, description="Broker for telemetry and commands.")
    failsafe: FailsafeSpec = Field(
        default=FailsafeSpec(), description="Bad telemetry and a lost link (wall s)."
    )

    @model_validator(mode="after")
    def _consistent(self) -> MissionProfile:
        levels = self.policy.levels
        if self.policy.kind != "mdm" and len(levels) != 1:
            raise ValueError(f"policy.kind {self.policy.kind!r} takes exactly one level")
        if self.policy.kind == "mdm" and len(levels) != len(self.sensors):
            raise ValueError(
                f"policy.kind 'mdm' needs one level per sensor: {len(levels)} levels, "
                f"{len(self.sensors)} sensors"
            )
        if self.policy.kind == "lm2" and len(self.sensors) < 2:
            raise ValueError("policy.kind 'lm2' needs a detection and a confirmation sensor")
        if levels[0].index is not None:
            raise ValueError("policy.levels[0] (level 1) takes no index: it never times out")
        for k, level in enumerate(levels[1:], start=1):
            if level.index is None:
                raise ValueError(f"policy.levels[{k}] needs an index (C_I or D_I)")
        radii = [s.radius for s in self.sensors]
        if any(a <= b for a, b in pairwise(radii)):
            raise ValueError(f"sensors must be ordered by decreasing radius, got {radii}")
        for t in self.targets:
            if not (0 <= t.north <= self.area.north and 0 <= t.east <= self.area.east):
                raise ValueError(f"target at ({t.north}, {t.east}) lies outside the area")
        if all(t.false_target for t in self.targets):
            raise ValueError("at least one target must be real")
        self._check_work()
        return self

    def _check_work(self) -> None:
        """Refuse combinations that are each valid but would take a vehicle more than
        MAX_LEGS legs (or swarm iterations) to simulate up to the longest mission time."""
        horizon = max(self.mission.duration, self.mission.ts_cap)
        shortest = min(level.step for level in self.policy.levels)
        legs = horizon * self.fleet.speed / shortest
        if legs > MAX_LEGS:
            raise ValueError(
                f"mission.ts_cap/duration ({horizon:g} s) x fleet.speed ({self.fleet.speed:g} m/s)"
                f" / the shortest policy.levels step ({shortest:g} m) = {legs:.3g} legs per "
                f"vehicle, more than {MAX_LEGS:g}: the simulation would not end"
            )
        if self.policy.kind in ("pso", "spso", "arpso"):
            iterations = horizon / self.policy.swarm.update_interval
            if iterations > MAX_LEGS:
                raise ValueError(
                    f"mission.ts_cap/duration ({horizon:g} s) / policy.swarm.update_interval "
                    f"({self.policy.swarm.update_interval:g} s) = {iterations:.3g} iterations, "
                    f"more than {MAX_LEGS:g}: the simulation would not end"
                )

    def with_policy(self, policy: PolicySpec) -> MissionProfile:
        """The same mission flown with another policy."""
        return self.model_copy(update={"policy": policy})
