"""The vehicles' active sensors against the world's targets, and the ground-truth events.

Only the sensor a vehicle's companion switched on (parameter MDM_SENSOR) reads; the world's
``contacts`` decides what it sees. Events go to the event log, never over MAVLink.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from mdm_core.world import Scenario, TargetTracks, contacts
from sim_vehicle_stub.departures import Departures
from sim_vehicle_stub.events import EventLog
from sim_vehicle_stub.readout_kernel import readout

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


class Reading(NamedTuple):
    """What one vehicle's active sensor reports at one tick."""

    sensor: int
    confirms: bool
    signal: float
    """Strongest exp(-d/r) over targets this sensor can see (0 when none is present)."""
    contacts: list[tuple[int, float, float, float]]
    """(target index, north, east, strength) of each target within the radius."""


class SensorWorld:
    """Targets of one run of the scenario and every vehicle's contact history."""

    def __init__(
        self, scenario: Scenario, tracks: TargetTracks, n_vehicles: int, events: EventLog
    ) -> None:
        self.scenario = scenario
        self.tracks = tracks
        self.events = events
        self.departures = Departures(scenario.targets, tracks, events)
        m = scenario.targets.count
        self.n_sensors = len(scenario.sensors)
        self._appeared = np.zeros(m, dtype=bool)
        self._in_range = np.zeros((n_vehicles, m, self.n_sensors), dtype=bool)
        self._detected = np.zeros((n_vehicles, m), dtype=bool)
        self._confirmed = np.zeros((n_vehicles, m), dtype=bool)
        self._static: FloatArray | None = None
        self._present = np.zeros(m, dtype=bool)
        """Targets that have appeared (recomputed when the next one is due)."""
        self._next_appearance = -math.inf
        # the readout kernel compiled or loaded now, not in the first tick of a running loop
        none = np.zeros(0, dtype=np.intp)
        readout(
            np.zeros((0, m), dtype=bool),
            np.zeros((0, m)),
            self._present,
            np.zeros(0, dtype=bool),
            scenario.targets.false_mask,
            self._in_range,
            none,
            none,
        )

    def targets_at(self, t: float) -> FloatArray:
        if not self.tracks.moving and self._static is not None:
            return self._static
        pos = self.tracks.positions(np.zeros(1, dtype=np.intp), np.array([t]))
        targets = np.asarray(pos[0], dtype=np.float64)
        if not self.tracks.moving:
            self._static = targets
        return targets

    def tick(
        self, t: float, vehicles: FloatArray, active: IntArray, radius: FloatArray
    ) -> dict[int, Reading]:
        """Readings of vehicles whose sensor is on; ``radius`` (n,) is each active radius."""
        spec = self.scenario.targets
        if t >= self._next_appearance:
            self._appear(t)
        self.departures.tick(t)
        on = np.flatnonzero(active >= 0)
        if len(on) == 0:
            return {}
        targets = self.targets_at(t)
        present = self._present
        sensor = active[on]
        confirms = sensor == self.n_sensors - 1
        # contacts() broadcasts (m,)-shaped targets and presence over the vehicles
        mask, strength = contacts(
            radius[on], confirms, vehicles[on], targets, present, spec.false_mask
        )
        strongest, entered = readout(
            mask, strength, present, confirms, spec.false_mask, self._in_range, on, sensor
        )
        signal = strongest.tolist()
        if entered.any():
            for row, k in zip(*np.nonzero(entered), strict=True):
                self._log_entry(t, int(on[row]), int(sensor[row]), int(k), targets)
        hits: dict[int, list[tuple[int, float, float, float]]] = {}
        if mask.any():
            for row, k in zip(*np.nonzero(mask), strict=True):
                hits.setdefault(int(row), []).append(
                    (int(k), float(targets[k, 0]), float(targets[k, 1]), float(strength[row, k]))
                )
        sensors, conf = sensor.tolist(), confirms.tolist()
        return {
            i: Reading(sensors[row], conf[row], signal[row], hits.get(row, []))
            for row, i in enumerate(on.tolist())
        }

    def _appear(self, t: float) -> None:
        """Targets whose time came: logged once, present from now on."""
        spec = self.scenario.targets
        self._present = spec.appear_times <= t
        targets = self.targets_at(t)
        for k in np.flatnonzero(self._present & ~self._appeared):
            self._appeared[k] = True
            self.events.write(
                t,
                "target_appeared",
                target=int(k),
                north=float(targets[k, 0]),
                east=float(targets[k, 1]),
                false_target=bool(spec.false_mask[k]),
            )
        later = spec.appear_times[~self._present]
        self._next_appearance = float(later.min()) if len(later) else math.inf

    def _log_entry(self, t: float, i: int, s: int, k: int, targets: FloatArray) -> None:
        name = self.scenario.sensors[s].name
        where = {"north": float(targets[k, 0]), "east": float(targets[k, 1])}
        self.events.write(t, "entered_range", vehicle=i, target=k, sensor=name, **where)
        is_conf = s == self.n_sensors - 1
        seen = self._confirmed if is_conf else self._detected
        if not seen[i, k]:
            seen[i, k] = True
            self.events.write(
                t, "confirmed" if is_conf else "detected", vehicle=i, target=k, sensor=name, **where
            )
