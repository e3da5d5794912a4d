"""The optional ``failsafe:`` section of a profile: what a companion does when the vehicle's
positions stop making sense or its link goes away (docs/model.md, "Telemetry checks and
failsafes")."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field


class FailsafeSpec(BaseModel):
    """Times are wall seconds: the vehicle's clock is what is missing when they run."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    position_timeout: float = Field(
        default=2.0,
        gt=0,
        le=3600,
        description="No valid position for this long (wall s) while flying: the vehicle is "
        "told to HOLD.",
    )
    position_hold: float = Field(
        default=10.0,
        ge=0,
        le=3600,
        description="Still none after this much more HOLD (wall s): the mission ends with its "
        "end action (RTL or land), exit status 1.",
    )
    link_wait: float = Field(
        default=30.0,
        gt=0,
        le=86400,
        description="A lost link (no HEARTBEAT) is waited for this long (wall s), then the "
        "companion ends with exit status 1.",
    )
    speed_margin: float = Field(
        default=2.0,
        ge=1,
        le=100,
        description="A position that moved faster than this times fleet.speed (plus 5 m), or "
        "reports such a velocity, is dropped.",
    )
