"""A profile as the engines fly it, built once per configuration and handed to each of its
blocks: the scenario, the compiled policy (the search of the event engine, the explorer of the
swarms), the swarm's rules and its signal radius. ``runner`` builds one per profile
(``configure``) before any block runs; a block reads the raw profile only for its plain
fields (fleet, mission)."""

from __future__ import annotations

from dataclasses import dataclass

from mdm_core.search.from_profile import policy_config, signal_radius, swarm_config
from mdm_core.search.pso import SwarmConfig
from mdm_core.world import Scenario
from mdm_montecarlo.kernels.policy_step import CompiledPolicy
from mdm_profiles import MissionProfile

SWARM_KINDS = ("pso", "spso", "arpso")
"""The social-cognitive baselines (mdm_montecarlo.engines.social_engine, waypoint_swarm)."""
LAWNMOWER_KINDS = ("lm1", "lm2")
"""The partitioned lawnmowers (mdm_montecarlo.engines.lawnmower_engine)."""


@dataclass(frozen=True)
class Configuration:
    """One profile's configuration, as every block of it reads it."""

    profile: MissionProfile
    scenario: Scenario
    policy: CompiledPolicy | None
    """The search policy, or the swarms' explorer (their level-1 waypoints); None for the
    lawnmowers, which draw none."""
    swarm: SwarmConfig | None
    """The swarm's rules (swarm_config) for pso/spso/arpso; else None."""
    signal_radius: float
    """The swarms' signal radius (from_profile.signal_radius); 0 for the other kinds."""

    @property
    def search(self) -> CompiledPolicy:
        """``policy``, for the engines that draw waypoints."""
        if self.policy is None:
            raise ValueError(f"policy.kind {self.profile.policy.kind} draws no waypoints")
        return self.policy

    @property
    def swarm_rules(self) -> SwarmConfig:
        """``swarm``, for the swarm engines."""
        if self.swarm is None:
            raise ValueError(f"policy.kind {self.profile.policy.kind} is not a swarm")
        return self.swarm


def is_swarm(profile: MissionProfile) -> bool:
    """Whether the profile's rows run on a swarm engine (PSO/SPSO/ARPSO)."""
    return profile.policy.kind in SWARM_KINDS


def configure(profile: MissionProfile) -> Configuration:
    """The profile's configuration: the only place a block's setup is read from the profile."""
    kind = profile.policy.kind
    swarm = is_swarm(profile)
    return Configuration(
        profile,
        Scenario.from_profile(profile),
        None if kind in LAWNMOWER_KINDS else CompiledPolicy(policy_config(profile)),
        swarm_config(profile) if swarm else None,
        signal_radius(profile) if swarm else 0.0,
    )
