"""The lawnmower baselines' fields of a profile (``policy.lawnmower``; policy.kind lm1 / lm2)."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field


class LawnmowerSpec(BaseModel):
    """How a partitioned lawnmower team sweeps (docs/model.md, "The lawnmower baseline")."""

    model_config = ConfigDict(extra="forbid")

    overlap: float = Field(
        default=0.0,
        ge=0.0,
        lt=1.0,
        description="Share of a lane's sensor swath shared with the next: lanes 2 r (1 - "
        "overlap) apart (r: the confirmation sensor's for lm1, the detection sensor's for lm2).",
    )
    search: Literal["spiral_in", "spiral_out"] = Field(
        default="spiral_in",
        description="lm2: the confirmation search after a detection: a spiral of rings 2 r2 "
        "apart over the detection disc, from its rim inwards or from its centre outwards.",
    )
    chords_per_turn: int = Field(
        default=32, ge=8, le=360, description="lm2: straight legs per turn of the spiral."
    )
    search_hold: float | None = Field(
        default=None,
        ge=0.0,
        description="lm2: after a search that did not confirm the target detected, that "
        "target's detections are ignored this long, s (None: until the pass over the cell "
        "ends, i.e. once per sweep).",
    )
