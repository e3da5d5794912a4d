"""Named readings of the paper: for each scenario, the documented variant (study.VARIANTS) its
rows fly. `reproduce --reading NAME` reports the reading's rows as the headline; `run` and
`sweep --reading NAME` fly the profile with the reading's choice for its scenario."""

from __future__ import annotations

import argparse
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TypeVar

from mdm_montecarlo.study.cases import RENEW_VARIANTS, VARIANTS, Case
from mdm_profiles import MissionProfile, ProfileError
from mdm_profiles.overrides import apply_overrides

SCENARIOS = ("fixed", "popup", "dynamic")
HELP = "help"
"""`--reading help` lists the readings and their choices."""


@dataclass(frozen=True)
class Reading:
    name: str
    about: str
    choices: Mapping[str, tuple[str, ...]]
    """Scenario -> the VARIANTS keys its rows fly, first choice first: a row not flown with the
    first (the renewed rows are MDM's alone: a single-sensor search has no level 2, so the
    choice is the next one for it) takes the next; none flown, or a scenario not named, the
    defaults."""

    def label(self) -> str:
        """The choices as text: 'popup: t_i = 200 (i - 1), dynamic: ...', or 'the defaults'."""
        parts = [f"{s}: {VARIANTS[keys[0]][0]}" for s, keys in self.choices.items()]
        return ", ".join(parts) or "the defaults"

    def overrides(self, scenario: str) -> tuple[str, ...]:
        """The profile overrides of the reading's first choice for ``scenario``."""
        keys = self.choices.get(scenario, ())
        return VARIANTS[keys[0]][1] if keys else ()


READINGS = {
    r.name: r
    for r in (
        Reading("default", "the defaults of every profile (docs/model.md, 'The open choices')", {}),
        Reading(
            "closest",
            "the documented choices that bring most rows inside tolerance without contradicting "
            "each other (docs/model.md, 'One reading of the paper')",
            {
                "fixed": (RENEW_VARIANTS["fixed"],),
                "popup": (RENEW_VARIANTS["popup"], "popup_from_0"),
                "dynamic": (RENEW_VARIANTS["dynamic"], "targets_leave"),
            },
        ),
    )
}
DEFAULT = "default"
CLOSEST = "closest"


def reading_named(name: str) -> Reading:
    """The reading called ``name``; a ValueError listing the readings otherwise."""
    if name not in READINGS:
        raise ValueError(
            f"--reading: unknown reading {name!r}; readings: {', '.join(READINGS)} "
            f"(--reading {HELP} lists their choices)"
        )
    return READINGS[name]


def readings_help() -> str:
    """What `--reading help` prints: every reading, what it is and its choices."""
    lines = ["Readings of the paper (--reading NAME):"]
    for r in READINGS.values():
        lines += [f"  {r.name}: {r.about}", f"    choices: {r.label()}"]
        for scenario, keys in r.choices.items():
            lines.append(f"    {scenario} overrides: {' '.join(VARIANTS[keys[0]][1])}")
    return "\n".join(lines)


class _ReadingAction(argparse.Action):
    """Stores the name; `--reading help` prints the readings and exits 0 (as --version does,
    before the other arguments are checked)."""

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: str | Sequence[object] | None,
        option_string: str | None = None,
    ) -> None:
        if values == HELP:
            print(readings_help())
            parser.exit(0)
        setattr(namespace, self.dest, values)


def add_reading_flag(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--reading",
        action=_ReadingAction,
        default=DEFAULT,
        metavar="NAME",
        help=f"a named reading of the paper: {', '.join(READINGS)} (default {DEFAULT}; "
        f"'--reading {HELP}' lists their choices)",
    )


def scenario_of(profile: MissionProfile) -> str:
    """'dynamic' with moving targets, 'popup' where a target appears after t = 0, else 'fixed'."""
    if profile.target_motion:
        return "dynamic"
    return "popup" if any(t.appear > 0 for t in profile.targets) else "fixed"


def with_reading(profile: MissionProfile, name: str) -> MissionProfile:
    """The profile with the reading's choice for its scenario; a ProfileError naming the
    reading and the choice where the profile cannot take it (e.g. fewer targets)."""
    reading = reading_named(name)
    scenario = scenario_of(profile)
    try:
        return apply_overrides(profile, list(reading.overrides(scenario)))
    except ProfileError as exc:
        raise ProfileError(
            f"--reading {name}: its {scenario} choice does not fit profile {profile.name!r}: {exc}"
        ) from None


T = TypeVar("T")


def reading_cases(results: Mapping[Case, T], name: str) -> dict[Case, T]:
    """``results`` with each default case's value replaced by its reading variant's, where
    ``results`` has that case (what the reading's figures are drawn from, under the default
    case's key)."""
    reading = reading_named(name)
    out = {}
    for case, value in results.items():
        if case.variant:
            continue
        flown = [
            replace(case, variant=k)
            for k in reading.choices.get(case.scenario, ())
            if replace(case, variant=k) in results
        ]
        out[case] = results[flown[0]] if flown else value
    return out
