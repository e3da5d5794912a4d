"""Small mission profiles for tests, written as files a `companion` or an emulator process reads:
one base and each test's changes to it, checked by the profile model and written by
:func:`mdm_profiles.write_profile` (which :func:`mdm_profiles.load_profile` reads back equal)."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

from mdm_profiles import MissionProfile, load_profile, write_profile


def sensors(detection: float, confirmation: float) -> list[dict[str, Any]]:
    """The two sensors, by radius (m): ``detection`` raises the level, ``confirmation``
    confirms."""
    return [
        {"name": "detection", "radius": detection},
        {"name": "confirmation", "radius": confirmation},
    ]


def levels(ls_step: float, bs_step: float, kappa: float) -> list[dict[str, Any]]:
    """The two MDM levels of every small profile: LS, then BS with the paper's index."""
    index = {"gamma": 0.1, "index_max": 0.95, "index_min": 0.2, "kappa": kappa}
    return [
        {"distribution": "LS", "step": ls_step},
        {"distribution": "BS", "step": bs_step, "index": index},
    ]


BASE: dict[str, Any] = {
    "area": {"north": 3000.0, "east": 3000.0},
    "targets": [
        {"north": 1500.0, "east": 1500.0},
        {"north": 600.0, "east": 2400.0, "false_target": True},
    ],
    "fleet": {"vehicles": 2, "speed": 20.0, "tau": 0.33, "altitude": 30.0, "altitude_step": 5.0},
    "sensors": sensors(1000.0, 50.0),
    "policy": {"kind": "mdm", "levels": levels(600.0, 1000.0, 150.0)},
    "mission": {"duration": 5000.0, "ts_cap": 5000.0},
}
"""A 3 km square, a real target in the middle and a false one, two vehicles, a 5000 s search."""


def _merged(base: dict[str, Any], changes: dict[str, Any]) -> dict[str, Any]:
    """``base`` with ``changes``: a dict merges into a dict key by key, anything else replaces."""
    out = copy.deepcopy(base)
    for key, value in changes.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = _merged(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def profile_with(name: str, **changes: Any) -> MissionProfile:
    """:data:`BASE` named ``name`` with ``changes`` (top-level sections of a profile file)."""
    return MissionProfile.model_validate(_merged(BASE, {"name": name, **changes}))


def write_profile_with(path: Path, name: str, **changes: Any) -> Path:
    """:func:`profile_with` written to ``path``; returns ``path``."""
    write_profile(profile_with(name, **changes), path)
    return path


def blind_field_search(name: str, vehicles: int, duration: float) -> dict[str, Any]:
    """field-duebendorf as a plain dict for a long SITL search that no target ends: one
    altitude layer for every vehicle, virtual sensors of a few metres and one real target in
    the area's far corner, the mission ``duration`` (and T_S cap) in vehicle s."""
    p = load_profile("field-duebendorf").model_dump(mode="json", exclude_none=True)
    p["name"] = name
    p["fleet"]["vehicles"] = vehicles
    p["fleet"]["altitude_step"] = 0.0
    p["sensor_source"] = {"kind": "virtual"}
    p["sensors"] = [
        {"name": "rf-detection", "radius": 3.0},
        {"name": "camera-confirmation", "radius": 1.0},
    ]
    p["targets"] = [{"north": 60.0, "east": 60.0}]
    p["mission"] = {"duration": duration, "ts_cap": duration}
    return p
