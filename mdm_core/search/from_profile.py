"""Build the search policy a mission profile describes."""

from __future__ import annotations

from mdm_core.search.distributions import Brownian, Levy, Sampler, Uniform
from mdm_core.search.levels import DecayIndex, Level, PolicyConfig
from mdm_core.search.pso import VARIANTS, SwarmConfig
from mdm_core.world.fence_planes import fence_half_planes
from mdm_profiles import MissionProfile
from mdm_profiles.schema import DistributionParams, LevelSpec


def sampler(name: str, params: DistributionParams) -> Sampler:
    """The direction sampler for LS, BS or US with the profile's parameters."""
    if name == "LS":
        return Levy(index=params.levy_index, scale=params.levy_scale)
    if name == "BS":
        return Brownian(sigma=params.brownian_sigma)
    if name == "US":
        return Uniform(low=params.uniform_low, high=params.uniform_high)
    raise ValueError(f"unknown distribution {name!r}; allowed: LS, BS, US")


def _level(spec: LevelSpec, radius: float, params: DistributionParams) -> Level:
    index = None
    if spec.index is not None:
        index = DecayIndex(
            gamma=spec.index.gamma,
            index_max=spec.index.index_max,
            index_min=spec.index.index_min,
            kappa=spec.index.kappa,
            start=spec.index.start,
        )
    return Level(
        sampler=sampler(spec.distribution, params),
        step=spec.step,
        sensor_radius=radius,
        index=index,
        step_law=spec.step_law,
        step_index=params.levy_index,
    )


def policy_config(profile: MissionProfile) -> PolicyConfig:
    """PolicyConfig of a profile: MDM uses sensor k on level k, SSS only the confirmation sensor.

    For the swarm kinds (pso, spso, arpso) it is the single-sensor search that explores until a
    particle has a best to follow.
    """
    spec = profile.policy
    radii = [s.radius for s in profile.sensors]
    if spec.kind != "mdm":
        radii = radii[-1:]
    levels = tuple(
        _level(lv, r, spec.distributions) for lv, r in zip(spec.levels, radii, strict=True)
    )
    return PolicyConfig(
        levels=levels,
        area=(profile.area.north, profile.area.east),
        out_of_area=spec.out_of_area,
        fence=fence_half_planes(profile),
        waypoint_origin=spec.waypoint_origin,
        confine_to_detection=spec.confine_to_detection,
        anchor_at=spec.anchor_at,
        redetection=spec.redetection,
        memory_radius=spec.memory_radius,
        detection_memory=spec.detection_memory,
        fallback_blind_time=spec.fallback_blind_time,
    )


def sensor_for_level(profile: MissionProfile, level: int) -> int:
    """Index into profile.sensors of the sensor switched on at ``level`` (0-based)."""
    if profile.policy.kind != "mdm":
        return len(profile.sensors) - 1
    return level


def signal_radius(profile: MissionProfile) -> float:
    """Range of the swarm's signal sensor: ``policy.swarm.signal_radius``, or else the radius
    of ``policy.swarm.signal_sensor``: the detection sensor's r_1 (the first sensor) or the
    confirmation sensor's r_2 (the last). Section IV: the swarms' sensor gives "a signal with
    strength proportional to the distance from the target" (docs/model.md, "Social-cognitive
    baselines")."""
    spec = profile.policy.swarm
    if spec.signal_radius is not None:
        return spec.signal_radius
    return profile.sensors[0 if spec.signal_sensor == "detection" else -1].radius


def swarm_config(profile: MissionProfile) -> SwarmConfig:
    """SwarmConfig of a pso/spso/arpso profile: steps clamped to speed x update interval."""
    kind = profile.policy.kind
    variant = next((v for v in VARIANTS if v == kind), None)
    if variant is None:
        raise ValueError(f"policy.kind {kind!r} is not a swarm variant; allowed: {VARIANTS}")
    spec = profile.policy.swarm
    return SwarmConfig(
        variant=variant,
        max_step=profile.fleet.speed * spec.update_interval,
        constant_speed=spec.constant_speed,
        inertia=spec.inertia,
        cognitive=spec.cognitive,
        social=spec.social,
        spso_inertia=spec.spso_inertia,
        spso_acceleration=spec.spso_acceleration,
        arpso_initial_inertia=spec.arpso_initial_inertia,
        arpso_speed_weight=spec.arpso_speed_weight,
        arpso_aggregation_weight=spec.arpso_aggregation_weight,
    )
