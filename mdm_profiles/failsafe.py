"""The optional ``failsafe:`` section of a profile: what a companion does when the vehicle's
positions stop making sense or its link goes away (docs/model.md, "Telemetry checks and
failsafes")."""

from __future__ import annotations

from typing import Literal

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
    safety_net: Literal["set", "check", "off"] | None = Field(
        default=None,
        description="The autopilot's own safety net before the first arm (fence action and "
        "ceiling, companion-loss and battery failsafes, RTL altitude): 'set' writes and reads "
        "back each parameter, 'check' refuses to arm (exit 2) when one is not as needed, "
        "'off' leaves them. Default: 'set' for profiles with a site, 'off' without.",
    )
    autopilot_battery: float = Field(
        default=10.0,
        gt=0,
        le=50,
        description="Battery left (%) at which the autopilot itself returns (its battery "
        "failsafe): under the companion's site.battery_min, which acts first while it runs.",
    )
    companion_loss: float = Field(
        default=5.0,
        ge=2,
        le=60,
        description="Wall s without the companion (heartbeat or setpoints) after which the "
        "autopilot returns by itself; written in the vehicle's seconds (x its clock rate).",
    )

    def safety_net_mode(self, has_site: bool) -> Literal["set", "check", "off"]:
        """The safety net's mode: as given, else 'set' with a site and 'off' without."""
        if self.safety_net is not None:
            return self.safety_net
        return "set" if has_site else "off"
