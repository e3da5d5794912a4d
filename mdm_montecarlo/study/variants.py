"""Named policy variants of section IV: 'US', 'BS', 'LS' (single sensor), 'MDM:LS+BS' etc., the
social-cognitive baselines 'PSO', 'SPSO', 'ARPSO', and the lawnmowers 'LM1', 'LM2'."""

from __future__ import annotations

from mdm_profiles import LevelSpec, MissionProfile, PolicySpec

METHODS = ("US", "BS", "LS")
SWARM_METHODS = ("PSO", "SPSO", "ARPSO")
LAWNMOWER_METHODS = ("LM1", "LM2")
"""The partitioned lawnmower baselines: LM1 sweeps with the confirmation sensor, LM2 with the
detection sensor and a confirmation search after each detection (docs/model.md)."""


def parse_method(text: str) -> tuple[str, tuple[str, ...]]:
    """'LS' -> ('sss', ('LS',)); 'MDM:LS+BS' -> ('mdm', ('LS', 'BS')); 'PSO' -> ('pso', ('US',));
    'MDM' alone -> ('mdm', ()): the profile's own MDM levels (``with_method`` fills them in).

    The swarm methods explore with US (the single-sensor uniform step) until they have a best.
    """
    text = text.strip().upper()
    if text in METHODS:
        return "sss", (text,)
    if text in SWARM_METHODS:
        return text.lower(), ("US",)
    if text in LAWNMOWER_METHODS:
        return text.lower(), ("US",)  # the level is unused: the plan fixes every waypoint
    if text == "MDM":
        return "mdm", ()
    if text.startswith("MDM:"):
        names = tuple(text[4:].split("+"))
        if names and all(n in METHODS for n in names):
            return "mdm", names
    raise ValueError(
        f"unknown method {text!r}; allowed: US, BS, LS, PSO, SPSO, ARPSO, LM1, LM2, "
        "MDM (the profile's levels) or MDM:<L1>+<L2>[+...] with L in US/BS/LS"
    )


def with_method(
    profile: MissionProfile, method: str, delta1: float | None = None
) -> MissionProfile:
    """The profile flown with another method; ``delta1`` overrides the level-1 step length (m).

    Single-sensor searches use the confirmation sensor with the level-1 step length of the
    profile (section IV: 20 % of L). MDM keeps the profile's deeper levels (step, index) and
    swaps the distributions.
    """
    kind, names = parse_method(method)
    current = profile.policy
    if kind == "mdm" and not names:
        if current.kind != "mdm":
            raise ValueError(
                f"{method}: the profile's policy is {current.kind!r}, not MDM; name the levels, "
                "e.g. MDM:LS+BS"
            )
        names = tuple(lv.distribution for lv in current.levels)
    step1 = delta1 if delta1 is not None else current.levels[0].step
    if kind != "mdm":
        levels = [LevelSpec(distribution=names[0], step=step1, step_law=current.levels[0].step_law)]
    else:
        if len(names) != len(profile.sensors):
            raise ValueError(
                f"{method}: needs one distribution per sensor ({len(profile.sensors)})"
            )
        template = current.levels if current.kind == "mdm" else None
        if template is None or len(template) != len(names):
            raise ValueError(
                f"{method}: the profile has no MDM levels to take steps and indices from"
            )
        levels = [
            lv.model_copy(update={"distribution": name, **({"step": step1} if k == 0 else {})})
            for k, (lv, name) in enumerate(zip(template, names, strict=True))
        ]
    spec = current.model_copy(update={"kind": kind, "levels": levels})
    return profile.with_policy(PolicySpec.model_validate(spec.model_dump()))


def with_fleet_size(profile: MissionProfile, vehicles: int) -> MissionProfile:
    """The profile with another number of vehicles."""
    fleet = profile.fleet.model_copy(update={"vehicles": vehicles})
    return profile.model_copy(update={"fleet": fleet})
