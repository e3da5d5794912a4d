"""Mission profiles: the validated schema and the YAML loader, shared by every layer."""

from mdm_profiles.errors import ProfilesError
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
from mdm_profiles.sensor_source import SensorSourceKind, SensorSourceSpec

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
    "ProfilesError",
    "RandomWalkSpec",
    "SensorSourceKind",
    "SensorSourceSpec",
    "SensorSpec",
    "TargetEntry",
    "builtin_profile",
    "builtin_profiles",
    "load_profile",
    "write_profile",
]
