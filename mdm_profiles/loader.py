"""Load and validate mission profiles from YAML; errors name the file, the field and what is allowed."""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import get_args

import yaml
from pydantic import BaseModel, ValidationError

from mdm_profiles.errors import ProfilesError
from mdm_profiles.schema import MissionProfile


class ProfileError(ProfilesError, ValueError):
    """A profile that cannot be used, with every problem listed as file: field: message."""


def _model_at(loc: tuple[int | str, ...]) -> type[BaseModel] | None:
    """The schema model that holds the field at ``loc`` (list indices and Optional skipped)."""
    model: type[BaseModel] = MissionProfile
    for part in loc:
        if isinstance(part, int):
            continue
        field = model.model_fields.get(part)
        if field is None:
            return None
        candidates = [field.annotation, *get_args(field.annotation)]
        candidates += [arg for c in candidates for arg in get_args(c)]
        nested = [c for c in candidates if isinstance(c, type) and issubclass(c, BaseModel)]
        if not nested:
            return None
        model = nested[0]
    return model


def describe_errors(source: str, error: ValidationError) -> str:
    lines = [f"{source}: invalid mission profile ({error.error_count()} problem(s))"]
    for item in error.errors():
        field = ".".join(str(p) for p in item["loc"]) or "(top level)"
        msg = item["msg"]
        if item["type"] == "extra_forbidden":
            msg = "unknown key (not part of the profile schema)"
            parent = _model_at(tuple(item["loc"][:-1]))
            if parent is not None:
                msg += f"; allowed: {', '.join(parent.model_fields)}"
        ctx = item.get("ctx") or {}
        if "expected" in ctx:
            msg += f"; allowed: {ctx['expected']}"
        given = item.get("input")
        if item["type"] != "missing" and not isinstance(given, dict | list):
            msg += f" (got {given!r})"
        lines.append(f"  {source}: {field}: {msg}")
    return "\n".join(lines)


_FAST_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
"""libyaml's safe loader where PyYAML was built with it: the same data, about 9x faster (the
98 profiles of `reproduce` took 1 CPU-s to parse with the pure-Python loader)."""


def _read_yaml(text: str) -> object:
    """Parse with the fast loader; on an error, parse again with the pure-Python one, whose
    message quotes the offending line and points at the column."""
    try:
        return yaml.load(text, Loader=_FAST_LOADER)
    except yaml.YAMLError:
        return yaml.safe_load(text)


def parse_profile(text: str, source: str) -> MissionProfile:
    """Validate YAML text; ``source`` names it in errors."""
    try:
        data = _read_yaml(text)
    except yaml.YAMLError as exc:
        raise ProfileError(f"{source}: not valid YAML: {exc}") from exc
    if not isinstance(data, dict):
        raise ProfileError(f"{source}: a profile is a YAML mapping, got {type(data).__name__}")
    try:
        return MissionProfile.model_validate(data)
    except ValidationError as exc:
        raise ProfileError(describe_errors(source, exc)) from None


def load_profile(path: str | Path) -> MissionProfile:
    """Load a profile from a file path, or a built-in profile by name (e.g. 'paper-fixed')."""
    p = Path(path)
    if not p.exists():
        names = builtin_profiles()
        if str(path) in names:
            return builtin_profile(str(path))
        raise ProfileError(f"{path}: no such file, and not a built-in profile ({', '.join(names)})")
    return parse_profile(p.read_text(encoding="utf-8"), str(p))


def write_profile(profile: MissionProfile, path: Path) -> None:
    """Write ``profile`` as YAML that :func:`load_profile` reads back equal (e.g. after --set)."""
    path.write_text(yaml.safe_dump(profile.model_dump(mode="json"), sort_keys=False))


def _builtin_dir() -> Path:
    return Path(str(resources.files("mdm_profiles") / "builtin"))


def builtin_profiles() -> list[str]:
    """Names of the profiles shipped with the package (mission_profiles/ in the repository)."""
    return sorted(p.stem for p in _builtin_dir().glob("*.yaml"))


def builtin_profile(name: str) -> MissionProfile:
    """A shipped profile by name."""
    path = _builtin_dir() / f"{name}.yaml"
    if not path.exists():
        raise ProfileError(f"{name}: not a built-in profile ({', '.join(builtin_profiles())})")
    return parse_profile(path.read_text(encoding="utf-8"), f"mission_profiles/{name}.yaml")
