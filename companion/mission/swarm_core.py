"""The live vehicle's adapter to the swarm baselines (PSO, SPSO, ARPSO): a particle of one.

Same interface as SearchCore (what VehicleMission calls). Every ``policy.swarm.update_interval``
vehicle seconds it runs one iteration of mdm_core.search.swarm_iteration, the code the
Monte-Carlo engine runs: the fitness is read from the confirmation sensor's SENS_SIG
(mdm_core.search.signal_reading), the peers' bests come from ``peers`` (MQTT, with the
profile's delay and loss), and the move is flown as a waypoint ``speed x interval`` away.
Confirmations are the confirmation sensor's contacts (DEBUG_VECT 'CNF'), one per target; a
target a peer reported confirmed is not confirmed again (as in the engine).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from companion.mission.search_core import Decision
from mdm_core.search import SearchPolicy
from mdm_core.search.from_profile import policy_config, signal_radius, swarm_config
from mdm_core.search.pso import (
    Best,
    BoolArray,
    FloatArray,
    forget,
    random_informants,
    swarm_best,
)
from mdm_core.search.signal_reading import attribute, fitness_from_signal
from mdm_core.search.swarm_iteration import (
    choose_move,
    explore,
    read_into_best,
    refresh_informants,
)
from mdm_profiles import MissionProfile

FIXED_TARGET_TOLERANCE_M = 10.0
"""How far (m) a reading's distance may be from a known fixed target's and still be it: the
vehicle moves about 2 m between a position and the SENS_SIG of the same tick."""


LIVE_READING = {
    "iteration": "interval",
    "after_confirmation": "forget",
    "read_confirmed": False,
}
"""The policy.swarm settings the live particle flies (the engine's 'swarm given MDM's
detection sensor' reading); the waypoint iteration and the kept memory are the engine's only."""


def live_swarm_refusal(profile: MissionProfile) -> str | None:
    """Why the live companion cannot fly ``profile``'s swarm settings (None if it can)."""
    spec = profile.policy.swarm
    wrong = [
        f"policy.swarm.{name} is {getattr(spec, name)!r}, not {value!r}"
        for name, value in LIVE_READING.items()
        if getattr(spec, name) != value
    ]
    if not wrong:
        return None
    return (
        f"profile {profile.name!r}: the live swarm flies one iteration per update interval and "
        f"forgets confirmed targets; {'; '.join(wrong)} (set them in the profile's "
        "policy.swarm, as mission_profiles/swarm-small.yaml does)"
    )


class SwarmExchange(Protocol):
    """The peers' side (companion.telemetry.mqtt.swarm_peers.SwarmPeers)."""

    def post(
        self,
        time: float,
        best: tuple[float, float],
        fitness: float,
        current: float,
        known: list[tuple[float, float]],
    ) -> None: ...

    def heard(self, now: float) -> tuple[Best, FloatArray]: ...

    def known(self) -> list[tuple[float, float]]: ...


class SwarmCore:
    """One particle: its bests, the last iteration's state and the vehicle's Generator."""

    def __init__(
        self,
        profile: MissionProfile,
        seed: int,
        vehicle: int,
        peers: SwarmExchange,
        signal: Callable[[], float],
    ) -> None:
        refusal = live_swarm_refusal(profile)
        if refusal is not None:
            raise ValueError(refusal)
        self.profile = profile
        self.config = swarm_config(profile)
        self.spec = profile.policy.swarm
        self.signal_radius = signal_radius(profile)
        self.explorer = SearchPolicy(policy_config(profile))
        self.rng = np.random.default_rng([seed, vehicle])
        self.peers = peers
        self.signal = signal
        self.vehicle = vehicle
        n = profile.fleet.vehicles
        self.tolerance = (
            FIXED_TARGET_TOLERANCE_M
            if profile.target_motion is None
            else profile.policy.memory_radius
        )
        self.own = Best(np.zeros((1, 2)), np.zeros(1), np.full(1, -1, dtype=np.intp))
        self.current = np.zeros(1)
        self.previous_best = np.zeros(1)
        self.guided = np.zeros(1, dtype=bool)
        self.links: BoolArray = np.arange(n)[None, :] != vehicle
        if self.config.variant == "spso":
            self.links = self._draw_informants()
        self.local_fitness = np.zeros(1)
        self.known: list[tuple[float, float]] = []
        """Targets known to be confirmed (own and peers'), where they were confirmed."""
        self.next_update = math.inf
        self.iterations = 0
        self.peer_bests_used = 0
        """Iterations that followed a best heard from a peer."""
        self._explore_to = np.zeros((1, 2))
        self._target = np.zeros((1, 2))
        self._last_position: FloatArray | None = None
        self.emit: Callable[..., Any] | None = None
        """Where to log (event name, fields) what the swarm does; set by the companion to the
        mission log's emit (VehicleMission.emit). Logged: ``swarm_follow`` for an iteration
        that follows a peer's best (own position, the best's position, fitness and peer)."""

    def start(self, position: FloatArray, time: float, memory: list[tuple[float, float]]) -> None:
        """First exploration waypoint at ``position``; ``memory``: targets confirmed earlier."""
        self.known = list(memory)
        self._explore_to = explore(self.explorer, position[None, :], self.rng)
        self._target = self._explore_to.copy()
        self.next_update = time

    @property
    def started(self) -> bool:
        return math.isfinite(self.next_update)

    @property
    def level(self) -> int:
        return 0

    @property
    def waypoint(self) -> FloatArray:
        return np.asarray(self._target[0])

    @property
    def confirmed_count(self) -> int:
        """Distinct targets the team is known to have confirmed (own and peers' reports)."""
        return len(self.known)

    def sensor(self) -> int:
        """The confirmation sensor: it confirms and its SENS_SIG is the fitness."""
        return len(self.profile.sensors) - 1

    def needs_step(
        self, time: float, position: FloatArray, reached: bool, contacts: FloatArray
    ) -> bool:
        return len(contacts) > 0 or time >= self.next_update

    def step(
        self, time: float, position: FloatArray, reached: bool, contacts: FloatArray
    ) -> Decision:
        """Confirm new contacts; at the update interval, one swarm iteration."""
        confirmed = self._confirm(contacts)
        iterate = time >= self.next_update
        if iterate:
            self._iterate(time, position)
        elif confirmed:
            self._publish(time)  # at once: the mission may end before the next iteration
        return Decision(
            level=0,
            previous_level=0,
            detected=False,
            confirmed=confirmed,
            fell_back=False,
            new_waypoint=iterate,
        )

    def index_value(self, time: float) -> float:
        return math.nan

    # -- internals -------------------------------------------------------------------------

    def _confirm(self, contacts: FloatArray) -> list[tuple[float, float]]:
        radius = self.profile.policy.memory_radius
        new: list[tuple[float, float]] = []
        for north, east in contacts.tolist():
            if all(math.hypot(north - n, east - e) > radius for n, e in self.known):
                self.known.append((north, east))
                new.append((north, east))
        return new

    def _iterate(self, time: float, position: FloatArray) -> None:
        here = position[None, :]
        heard, heard_current = self.peers.heard(time)
        self._confirm(np.array(self.peers.known()).reshape(-1, 2))
        known = np.array(self.known).reshape(-1, 2)
        is_known = np.ones((1, max(len(known), 1)), dtype=bool) & (len(known) > 0)
        fitness = fitness_from_signal(
            self.signal(),
            self.profile.sensors[-1].radius,
            self.signal_radius,
            position,
            known,
            self.tolerance,
        )
        self.current = np.array([fitness])
        own = attribute(self.own, self.signal_radius, known, self.tolerance)
        self.own, self.previous_best = read_into_best(
            own, is_known, here, self.current, np.full(1, -1, dtype=np.intp)
        )
        heard = forget(
            attribute(heard, self.signal_radius, known, self.tolerance),
            np.broadcast_to(is_known[:, None, :], (*heard.fitness.shape, is_known.shape[-1])),
        )
        self._publish(time)
        if self.config.variant == "spso":
            self.links, self.local_fitness = refresh_informants(
                self.own, heard, self.links, self.local_fitness, self._draw_informants
            )
        if not self.guided[0] and _near(self._explore_to[0], position, self._acceptance):
            self._explore_to = explore(self.explorer, here, self.rng)
        last = here if self._last_position is None else self._last_position
        move, self.guided, from_peer = choose_move(
            self.config,
            self.explorer,
            position=here,
            step=here - last,
            waypoint=self._explore_to,
            guided=self.guided,
            own=self.own,
            heard=heard,
            heard_current=heard_current,
            current=self.current,
            previous_best=self.previous_best,
            links=self.links,
            distance=self.profile.fleet.speed * self.spec.update_interval,
            rng=self.rng,
        )
        area = np.array([self.profile.area.north, self.profile.area.east])
        self._target = np.clip(here + move, 0.0, area)
        self._last_position = here
        self.iterations += 1
        self.peer_bests_used += int(from_peer[0])
        if from_peer[0] and self.emit is not None:
            self._log_follow(heard, position)
        self.next_update = time + self.spec.update_interval

    def _publish(self, time: float) -> None:
        best = (float(self.own.position[0, 0]), float(self.own.position[0, 1]))
        self.peers.post(
            time, best, float(self.own.fitness[0]), float(self.current[0]), list(self.known)
        )

    def _log_follow(self, heard: Best, position: FloatArray) -> None:
        social, _ = swarm_best(self.own, heard, self.links)
        peer = int(np.argmax(np.where(self.links, heard.fitness, -np.inf)[0]))
        assert self.emit is not None
        self.emit(
            "swarm_follow",
            peer=peer,
            fitness=round(float(social.fitness[0]), 4),
            best=[round(float(v), 1) for v in social.position[0]],
            pos=[round(float(v), 1) for v in position],
        )

    @property
    def _acceptance(self) -> float:
        return self.profile.fleet.acceptance_radius

    def _draw_informants(self) -> BoolArray:
        n = self.profile.fleet.vehicles
        rows = random_informants(self.rng, (), n, self.spec.informants)
        return np.asarray(rows[self.vehicle][None, :], dtype=bool)


def _near(a: FloatArray, b: FloatArray, radius: float) -> bool:
    return float(np.hypot(*(a - b))) <= radius
