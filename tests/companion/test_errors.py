"""Every error the companion defines derives from CompanionError (one except clause catches
them all) and keeps its builtin base; the public API raises them for bad input."""

from __future__ import annotations

import importlib
import inspect
import pkgutil

import pytest

import companion
from companion.errors import CompanionError, InputError
from companion.link.address import parse_address
from companion.link.factory import make_link


def _companion_errors() -> list[type[BaseException]]:
    found = []
    for module in pkgutil.walk_packages(companion.__path__, "companion."):
        loaded = importlib.import_module(module.name)
        for _, value in inspect.getmembers(loaded, inspect.isclass):
            if issubclass(value, BaseException) and value.__module__ == module.name:
                found.append(value)
    return found


def test_every_companion_error_derives_from_the_root() -> None:
    errors = _companion_errors()
    assert len(errors) >= 8  # the walk found the modules (LinkError, CommandError, ...)
    strays = [
        f"{e.__module__}.{e.__qualname__}" for e in errors if not issubclass(e, CompanionError)
    ]
    assert strays == []


@pytest.mark.parametrize(
    "url",
    [
        "udpin:0.0.0.0",
        "serial:/dev/ttyUSB0:fast",
        "serial::57600",
        "udpin:0.0.0.0:port",
        "tcp:h:70000",
    ],
)
def test_a_bad_address_is_an_input_error_naming_it(url: str) -> None:
    with pytest.raises(InputError, match="connection") as raised:
        parse_address(url)
    assert url in str(raised.value)
    assert isinstance(raised.value, ValueError)  # callers catching ValueError still catch it


def test_make_link_refuses_signing_on_mavsdk_and_a_bad_url_with_input_errors() -> None:
    with pytest.raises(InputError, match="cannot sign"):
        make_link(
            "mavsdk", url="udpin:0.0.0.0:14540", target_system=1, tlog=None, signing_key=bytes(32)
        )
    with pytest.raises(InputError, match="port"):
        make_link("pymavlink", url="udpin:0.0.0.0:x", target_system=1, tlog=None)
