"""Mission profiles: the validated schema and the YAML loader, shared by every layer."""

from mdm_profiles.loader import (
    ProfileError,
    builtin_profile,
    builtin_profiles,
    load_profile,
    write_profile,
)
from mdm_profiles.schema import (
    DecayIndexSpec,
    DistributionParams,
    FleetSpec,
    LevelSpec,
    MissionProfile,
    MissionSpec,
    Origin,
    PolicySpec,
    RandomWalkSpec,
    SensorSpec,
    TargetEntry,
)

__all__ = [
    "DecayIndexSpec",
    "DistributionParams",
    "FleetSpec",
    "LevelSpec",
    "MissionProfile",
    "MissionSpec",
    "Origin",
    "PolicySpec",
    "ProfileError",
    "RandomWalkSpec",
    "SensorSpec",
    "TargetEntry",
    "builtin_profile",
    "builtin_profiles",
    "load_profile",
    "write_profile",
]
