"""Profile section of the social-cognitive baselines (PSO, SPSO, ARPSO): policy.swarm.

Every field is a modelling choice the paper leaves open; docs/model.md ("Social-cognitive
baselines") gives the sources, the defaults and their measured effect.
"""

from __future__ import annotations

import math

from pydantic import BaseModel, ConfigDict, Field


class SwarmSpec(BaseModel):
    """Particle-swarm parameters. Lengths in metres, times in seconds."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    signal_radius: float | None = Field(
        default=None,
        gt=0,
        description="Range r of the sensor whose strength exp(-d / r) is the fitness, m; it "
        "reads targets nearer than r (eq. 5). Default (null): the detection sensor's, r_1 = "
        "the first sensor's radius, so the signal reaches beyond the confirmation radius.",
    )
    update_interval: float = Field(
        default=5.0,
        ge=0.1,
        le=600,
        description="Time between two velocity updates (one PSO iteration), s (0.1 to 600).",
    )
    constant_speed: bool = Field(
        default=True,
        description="Fly every PSO step at the fleet speed (Assumption II); false: clamp only.",
    )
    inertia: float = Field(default=0.7298, ge=0, description="PSO inertia weight w.")
    cognitive: float = Field(default=1.49618, ge=0, description="PSO/ARPSO c1 (personal best).")
    social: float = Field(default=1.49618, ge=0, description="PSO/ARPSO c2 (swarm best).")
    spso_inertia: float = Field(default=1.0 / (2.0 * math.log(2.0)), ge=0, description="SPSO w.")
    spso_acceleration: float = Field(default=0.5 + math.log(2.0), ge=0, description="SPSO c.")
    informants: int = Field(
        default=3, ge=1, description="SPSO adaptive random topology: informants per particle."
    )
    arpso_initial_inertia: float = Field(default=1.0, ge=0, description="ARPSO w_ini.")
    arpso_speed_weight: float = Field(
        default=0.5, ge=0, description="ARPSO alpha: weight of the evolution speed factor."
    )
    arpso_aggregation_weight: float = Field(
        default=0.4, ge=0, description="ARPSO beta: weight of the aggregation degree factor."
    )
    message_drop: float = Field(
        default=0.0, ge=0, le=1, description="Probability that a shared-best message is lost."
    )
    message_delay: float = Field(
        default=0.0,
        ge=0,
        le=3600,
        description="Delay of shared-best messages, s (whole update intervals; at most 3600).",
    )
