"""Dotted-path overrides of a profile ('policy.levels.1.index.kappa=300'), validated like a file."""

from __future__ import annotations

from typing import Any

import yaml
from pydantic import ValidationError

from mdm_profiles.loader import ProfileError, describe_errors
from mdm_profiles.schema import MissionProfile


def apply_overrides(profile: MissionProfile, assignments: list[str]) -> MissionProfile:
    """The profile with each 'dotted.path=value' applied (values parsed as YAML scalars)."""
    data: dict[str, Any] = profile.model_dump()
    for item in assignments:
        path, sep, raw = item.partition("=")
        if not sep or not path:
            raise ProfileError(f"--set {item!r}: expected dotted.path=value")
        keys = path.split(".")
        node: Any = data
        for key in keys[:-1]:
            node = node[int(key)] if isinstance(node, list) else node.setdefault(key, {})
            if node is None:
                raise ProfileError(f"--set {item!r}: {key} is not set in this profile")
        last = keys[-1]
        value = yaml.safe_load(raw)
        if isinstance(node, list):
            node[int(last)] = value
        else:
            node[last] = value
    try:
        return MissionProfile.model_validate(data)
    except ValidationError as exc:
        raise ProfileError(describe_errors(f"{profile.name} with --set", exc)) from None
