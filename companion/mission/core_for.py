"""The decision core a profile's policy kind flies: SearchCore (mdm, sss), SwarmCore (pso,
spso, arpso) or LawnmowerCore (lm1, lm2), behind the interface VehicleMission calls."""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from companion.geofence import Geofence
from companion.mission.config import MissionConfig
from companion.mission.lawnmower_core import LawnmowerCore
from companion.mission.search_core import Decision, SearchCore
from companion.mission.swarm_core import SwarmCore, SwarmExchange
from mdm_core.search.pso import VARIANTS, FloatArray


class MissionCore(Protocol):
    """What VehicleMission asks of its decision core."""

    def start(
        self, position: FloatArray, time: float, memory: list[tuple[float, float]]
    ) -> None: ...

    @property
    def started(self) -> bool: ...

    @property
    def level(self) -> int: ...

    @property
    def waypoint(self) -> FloatArray: ...

    @property
    def confirmed_count(self) -> int: ...

    def sensor(self) -> int: ...

    def needs_step(
        self, time: float, position: FloatArray, reached: bool, contacts: FloatArray
    ) -> bool: ...

    def step(
        self, time: float, position: FloatArray, reached: bool, contacts: FloatArray
    ) -> Decision: ...

    def index_value(self, time: float) -> float: ...


LAWNMOWER_KINDS = ("lm1", "lm2")
"""The partitioned lawnmower baselines (LawnmowerCore)."""


def is_swarm(config: MissionConfig) -> bool:
    return config.profile.policy.kind in VARIANTS


def core_for(
    config: MissionConfig,
    signal: Callable[[], float],
    peers: SwarmExchange | None,
    fence: Geofence,
) -> MissionCore:
    """The core of ``config``'s policy kind; ``signal``: the active sensor's latest SENS_SIG,
    ``peers``: the swarm exchange (required by the swarm kinds), ``fence``: the guidance fence
    (the lawnmower's lanes are cut to it)."""
    if config.profile.policy.kind in LAWNMOWER_KINDS:
        return LawnmowerCore(config.profile, config.seed, config.vehicle, fence)
    if not is_swarm(config):
        return SearchCore(config.profile, config.seed, config.vehicle)
    if peers is None:
        raise ValueError(
            f"profile {config.profile.name!r}: policy.kind {config.profile.policy.kind!r} "
            "shares the swarm's bests over MQTT; configure a broker (--mqtt HOST[:PORT] or "
            "the profile's mqtt: section)"
        )
    return SwarmCore(config.profile, config.seed, config.vehicle, peers, signal)
