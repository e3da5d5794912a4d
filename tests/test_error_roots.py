"""Every error class a package defines derives from that package's root (one except clause
catches them all) and keeps the builtin base its callers catch."""

from __future__ import annotations

import importlib
import inspect
import pkgutil

import pytest

from mavlink_conformance.errors import ConformanceError
from mavlink_conformance.session import LinkClosedError
from mavlink_wire import SigningError, SigningKeyError
from mdm_ground.errors import GroundError
from mdm_montecarlo.errors import MontecarloError
from mdm_profiles import ProfileError, ProfilesError

ROOTS: dict[str, type[Exception]] = {
    "mdm_montecarlo": MontecarloError,
    "mdm_ground": GroundError,
    "mdm_profiles": ProfilesError,
    "mavlink_wire": SigningError,
    "mavlink_conformance": ConformanceError,
}


def _errors_defined_in(package: str) -> list[type[BaseException]]:
    found = []
    path = importlib.import_module(package).__path__
    for module in pkgutil.walk_packages(path, f"{package}."):
        loaded = importlib.import_module(module.name)
        for _, value in inspect.getmembers(loaded, inspect.isclass):
            if issubclass(value, BaseException) and value.__module__ == module.name:
                found.append(value)
    return found


@pytest.mark.parametrize("package", sorted(ROOTS))
def test_every_error_of_a_package_derives_from_its_root(package: str) -> None:
    errors = _errors_defined_in(package)
    assert len(errors) >= 2  # the walk found the modules: the root and one error at least
    strays = [
        f"{e.__module__}.{e.__qualname__}" for e in errors if not issubclass(e, ROOTS[package])
    ]
    assert strays == []


@pytest.mark.parametrize(
    ("error", "builtin"),
    [(ProfileError, ValueError), (SigningKeyError, ValueError), (LinkClosedError, ConnectionError)],
)
def test_the_errors_keep_the_builtin_base_callers_catch(
    error: type[Exception], builtin: type[Exception]
) -> None:
    assert issubclass(error, builtin)
