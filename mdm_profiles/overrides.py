"""Dotted-path overrides of a profile ('policy.levels.1.index.kappa=300'), validated like a file."""

from __future__ import annotations

from typing import Any

import yaml
from pydantic import ValidationError

from mdm_profiles.loader import ProfileError, describe_errors
from mdm_profiles.schema import MissionProfile


def _index(node: list[Any], key: str, item: str, where: list[str]) -> int:
    """``key`` as an index into the list ``node`` found at ``where``; a ProfileError naming the
    path and the valid range otherwise (not an IndexError traceback)."""
    name = ".".join(where)
    try:
        i = int(key)
    except ValueError:
        raise ProfileError(
            f"--set {item!r}: {name} is a list; expected an index, got {key!r}"
        ) from None
    if not 0 <= i < len(node):
        raise ProfileError(
            f"--set {item!r}: {name} has {len(node)} entries (0 to {len(node) - 1}), no {i}"
        )
    return i


def apply_overrides(profile: MissionProfile, assignments: list[str]) -> MissionProfile:
    """The profile with each 'dotted.path=value' applied (values parsed as YAML scalars)."""
    data: dict[str, Any] = profile.model_dump()
    for item in assignments:
        path, sep, raw = item.partition("=")
        if not sep or not path:
            raise ProfileError(f"--set {item!r}: expected dotted.path=value")
        keys = path.split(".")
        node: Any = data
        for depth, key in enumerate(keys):
            last = depth == len(keys) - 1
            if isinstance(node, list):
                i = _index(node, key, item, keys[:depth])
                if last:
                    node[i] = yaml.safe_load(raw)
                else:
                    node = node[i]
            elif isinstance(node, dict):
                if last:
                    node[key] = yaml.safe_load(raw)
                else:
                    node = node.setdefault(key, {})
            else:
                where = ".".join(keys[:depth])
                raise ProfileError(
                    f"--set {item!r}: {where} is not set in this profile or is not a section"
                )
    try:
        return MissionProfile.model_validate(data)
    except ValidationError as exc:
        raise ProfileError(describe_errors(f"{profile.name} with --set", exc)) from None
