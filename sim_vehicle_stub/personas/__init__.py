"""Autopilot personas (PX4, ArduPilot Copter) behind one base class and a registry."""

from sim_vehicle_stub.personas.base import Action, Behaviour, ModeSpec, Persona, ProfileFacts
from sim_vehicle_stub.personas.registry import create_persona, persona_names, register

__all__ = [
    "Action",
    "Behaviour",
    "ModeSpec",
    "Persona",
    "ProfileFacts",
    "create_persona",
    "persona_names",
    "register",
]
