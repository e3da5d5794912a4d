"""The live vehicle's adapter to the shared search policy: a batch of one, in vehicle time."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mdm_core.search import Observation, SearchPolicy
from mdm_core.search.from_profile import policy_config, sensor_for_level
from mdm_core.search.policy import PolicyState
from mdm_profiles import MissionProfile

FloatArray = NDArray[np.float64]
_LANE = np.array([0])


@dataclass(frozen=True)
class Decision:
    """What one policy step changed for this vehicle."""

    level: int
    previous_level: int
    detected: bool
    confirmed: list[tuple[float, float]]
    fell_back: bool
    new_waypoint: bool


class SearchCore:
    """SearchPolicy + its state + the vehicle's Generator."""

    def __init__(self, profile: MissionProfile, seed: int, vehicle: int) -> None:
        self.profile = profile
        self.policy = SearchPolicy(policy_config(profile))
        self.rng = np.random.default_rng([seed, vehicle])
        self.state: PolicyState | None = None
        self.deadline = np.inf

    def start(self, position: FloatArray, time: float, memory: list[tuple[float, float]]) -> None:
        """Fresh state at ``position``, remembering targets confirmed by an earlier run."""
        self.state = self.policy.start(position[None, :], np.array([time]), self.rng)
        for north, east in memory:
            self.policy.remember(self.state, _LANE, np.array([[north, east]]))
        self.deadline = float(self.policy.deadline(self.state)[0])

    @property
    def started(self) -> bool:
        return self.state is not None

    @property
    def level(self) -> int:
        return int(self.state.level[0]) if self.state is not None else 0

    @property
    def waypoint(self) -> FloatArray:
        assert self.state is not None
        return np.asarray(self.state.waypoint[0])

    @property
    def confirmed_count(self) -> int:
        return int(self.state.memory_count[0]) if self.state is not None else 0

    def sensor(self) -> int:
        """Index of the sensor this level switches on."""
        return sensor_for_level(self.profile, self.level)

    def needs_step(
        self, time: float, position: FloatArray, reached: bool, contacts: FloatArray
    ) -> bool:
        """Whether :meth:`step` would change anything: never without contacts, the waypoint
        reached or C_I run out; with contacts, only where the policy says (a target it
        confirmed itself, read again, changes nothing)."""
        if not (reached or len(contacts) > 0 or time >= self.deadline):
            return False
        assert self.state is not None
        contacts = _distinct(contacts, self.policy.config.memory_radius)
        here = (float(position[0]), float(position[1]))
        return self.policy.step_changes(self.state, 0, time, here, reached, contacts)

    def step(
        self, time: float, position: FloatArray, reached: bool, contacts: FloatArray
    ) -> Decision:
        """One policy step of the shared SearchPolicy."""
        assert self.state is not None
        before = self.level
        contacts = _distinct(contacts, self.policy.config.memory_radius)
        m = len(contacts)
        obs = Observation(
            time=np.array([time]),
            position=position[None, :],
            reached=np.array([reached]),
            contacts=np.ones((1, m), dtype=bool),
            contact_positions=contacts.reshape(1, m, 2),
        )
        out = self.policy.step(self.state, _LANE, obs, self.rng)
        self.deadline = float(self.policy.deadline(self.state)[0])
        new = np.flatnonzero(out.new_confirmations[0])
        return Decision(
            level=self.level,
            previous_level=before,
            detected=bool(out.detected[0]),
            confirmed=[(float(contacts[j, 0]), float(contacts[j, 1])) for j in new],
            fell_back=bool(out.fell_back[0]),
            new_waypoint=bool(out.new_waypoint[0]),
        )

    def index_value(self, time: float) -> float:
        assert self.state is not None
        return float(self.policy.index_value(self.state, np.array([time]))[0])


def _distinct(points: FloatArray, radius: float) -> FloatArray:
    """Keep one reading per target: drop points within ``radius`` of an earlier kept one."""
    if len(points) < 2:
        return points
    kept: list[FloatArray] = []
    for p in points[::-1]:  # newest reading first
        if all(float(np.hypot(*(p - q))) > radius for q in kept):
            kept.append(p)
    return np.array(kept[::-1])
