"""The speed of the autopilot's own return, read once the vehicle is located (on the ground
before the first arm, or taken over in flight): the battery reserve counts the way home at
the slower of it and the profile's return speed (PX4 returns at MPC_XY_CRUISE, stock 5 m/s,
whatever the profile says; a rule counting 10 m/s left a PX4 SITL vehicle 1 % at touch-down).
docs/companion.md, "Battery"."""

from __future__ import annotations

import logging

from companion.mission.flown import Flown

log = logging.getLogger(__name__)


async def learn_return_speed(m: Flown) -> None:
    """Read the autopilot's return speed into ``m.seen.return_speed`` and record it
    (``return_speed``), where a reserve rule flies home horizontally."""
    rule, ap = m.config.battery_reserve, m.link.autopilot
    if rule is None or rule.horizontal <= 0 or ap is None:
        return
    for name, per_ms in ap.return_speed_params:
        value = await m.link.read_param(name)
        if value is None or value <= 0:
            continue
        speed = value / per_ms
        m.seen.return_speed = speed
        counted = rule.at_most(speed).horizontal
        m.emit("return_speed", param=name, value=value, speed=round(speed, 2), counted=counted)
        if counted < rule.horizontal:
            log.warning(
                "vehicle %d: the autopilot returns at %g m/s (%s %g), slower than the profile's "
                "%g m/s: the battery reserve counts the way home at %g m/s (raise %s, or set "
                "site.return_speed)",
                m.config.vehicle, speed, name, value, rule.horizontal, counted, name,
            )  # fmt: skip
        return
