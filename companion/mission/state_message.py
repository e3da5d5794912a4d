"""The MQTT state message of one vehicle: what it is doing now (docs/mqtt.md, ``state``)."""

from __future__ import annotations

import math

from companion.autopilots import Autopilot
from companion.mission.core_for import MissionCore
from companion.mission.observed import Observed
from companion.mission.phase import Phase


def state_message(
    vehicle: int,
    sensor_names: list[str],
    seen: Observed,
    core: MissionCore,
    phase: Phase,
    autopilot: Autopilot | None,
) -> dict[str, object]:
    """The message's fields; a position, mode or battery not known yet is left out or null."""
    pos, hb, st, t = seen.position, seen.heartbeat, seen.status, seen.clock.now
    ci = core.index_value(t) if core.started else math.nan
    sensor = core.sensor()
    mode = None
    if hb is not None and autopilot is not None:
        mode = autopilot.mode_name(hb.custom_mode)
    return {
        "vehicle": vehicle,
        "t": round(t, 3),
        "phase": phase.value,
        "mode": mode,
        "armed": hb.armed if hb is not None else None,
        "level": core.level,
        "sensor": sensor,
        "sensor_name": sensor_names[sensor],
        "ci": None if math.isnan(ci) else round(ci, 4),
        "found": core.confirmed_count,
        # SYS_STATUS battery_remaining, percent; -1 (the autopilot does not know): null
        "battery": None if st is None or st.battery_remaining < 0 else st.battery_remaining,
        **(
            {}
            if pos is None
            else {
                "north": round(pos.north, 1),
                "east": round(pos.east, 1),
                "alt": round(-pos.down, 1),
            }
        ),
    }
