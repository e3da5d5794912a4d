"""Pure MDM search decision core: distributions, levels, the batched policy, PSO.

The reference implementation of the search: the companion runs it; the Monte-Carlo engine's
compiled twins (mdm_montecarlo) are tested bit for bit against it (docs/architecture.md, "The
search policy and its compiled twins")."""

from mdm_core.search.distributions import Brownian, Levy, Sampler, Uniform, directions
from mdm_core.search.levels import DecayIndex, Level, PolicyConfig
from mdm_core.search.policy import Observation, PolicyState, SearchPolicy, StepOutcome

__all__ = [
    "Brownian",
    "DecayIndex",
    "Level",
    "Levy",
    "Observation",
    "PolicyConfig",
    "PolicyState",
    "Sampler",
    "SearchPolicy",
    "StepOutcome",
    "Uniform",
    "directions",
]
