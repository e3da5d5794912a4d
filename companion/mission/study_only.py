"""Profile settings the Monte-Carlo engine flies and a live vehicle cannot: refused by the
companion and by the fleet before anything starts."""

from __future__ import annotations

from mdm_profiles import MissionProfile


def study_only_refusal(profile: MissionProfile) -> str | None:
    """Why a live vehicle cannot fly ``profile`` (None: it can). policy.redetection reads the
    detection sensor on the last level, and the companion switches on one sensor per level."""
    rule = profile.policy.redetection
    if rule == "ignore":
        return None
    return (
        f"profile {profile.name!r}: policy.redetection {rule!r} reads the detection sensor on "
        "the last level, and the companion switches on one sensor per level; it is a "
        "Monte-Carlo study option (mdm-montecarlo run/reproduce), set it to 'ignore' to fly"
    )
