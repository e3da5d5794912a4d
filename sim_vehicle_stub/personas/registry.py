"""Personas by name, so a vehicle's autopilot is chosen by a string on the command line."""

from __future__ import annotations

from sim_vehicle_stub.personas.ardupilot import ArduCopterPersona
from sim_vehicle_stub.personas.base import Persona
from sim_vehicle_stub.personas.px4 import Px4Persona

_REGISTRY: dict[str, type[Persona]] = {}


def register(cls: type[Persona]) -> type[Persona]:
    """Make a persona class available under its ``name``."""
    _REGISTRY[cls.name] = cls
    return cls


def persona_names() -> list[str]:
    return sorted(_REGISTRY)


def create_persona(name: str) -> Persona:
    """A persona instance by name; raises ValueError naming the known ones."""
    try:
        return _REGISTRY[name]()
    except KeyError:
        raise ValueError(f"unknown persona {name!r}; known: {', '.join(persona_names())}") from None


register(Px4Persona)
register(ArduCopterPersona)
