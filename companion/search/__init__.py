"""Pure MDM search decision core: distributions, levels, the batched policy."""

from companion.search.distributions import Brownian, Levy, Sampler, Uniform, directions
from companion.search.levels import DecayIndex, Level, PolicyConfig
from companion.search.policy import Observation, PolicyState, SearchPolicy, StepOutcome

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
