"""The safety net put into the autopilot before the first arm (``failsafe.safety_net``): the
fence's breach action and ceiling, the companion-loss and battery failsafes, the RTL altitude in
the vehicle's layer, each parameter read, written where needed and read back (``set``), or only
checked (``check``: a wrong one refuses the start, exit 2). The autopilot lists its own
(companion/autopilots/*.py); what each does: docs/companion.md."""

from __future__ import annotations

import asyncio
import logging
import math
import time

from companion.autopilots.safety_params import SafetyNeeds, SafetyParam
from companion.mission.flown import Flown
from companion.mission.layer_watch import LAYER_TOLERANCE_M
from mdm_profiles.ceiling import ceiling

log = logging.getLogger(__name__)

SAFETY_NET_REFUSED = "refused: safety net: "
"""The end reason of a vehicle whose safety net is not as needed (the companion exits 2)."""
_RATE_WALL_S = 2.0
"""Wall s over which the vehicle's clock rate is measured (a simulator's speed-up): the loss
times are written in the vehicle's seconds."""
_FENCE_WAIT_S = 60.0
"""Vehicle s the safety net waits for the fence upload to end (both write the fence type)."""


async def install_safety_net(m: Flown) -> bool:
    """True when the vehicle may arm; else the mission was asked to end with the refusal."""
    profile = m.config.profile
    mode = profile.failsafe.safety_net_mode(profile.site is not None)
    v = m.config.vehicle
    if mode == "off":
        m.emit("safety_net", mode=mode)
        return True
    ap = m.link.autopilot
    assert ap is not None  # the lifecycle prepares only a vehicle it heard
    fence = m.vehicle_fence
    if fence is not None:
        await m.waits.until(lambda: fence.settled, _FENCE_WAIT_S)
    wall0, t0 = time.monotonic(), m.seen.clock.now
    read: dict[str, float | None] = {}
    for name in ap.safety_reads:
        read[name] = await m.link.read_param(name)
        older = ap.safety_fallbacks.get(name)
        if read[name] is None and older is not None:
            read[older] = await m.link.read_param(older)
    await asyncio.sleep(max(0.0, _RATE_WALL_S - (time.monotonic() - wall0)))
    rate = max(1.0, round((m.seen.clock.now - t0) / (time.monotonic() - wall0), 1))
    failsafe = profile.failsafe
    needs = SafetyNeeds(
        ceiling=ceiling(profile),
        layer=m.config.altitude,
        layer_band=LAYER_TOLERANCE_M,
        companion_id=m.link.own_system,
        battery=failsafe.autopilot_battery / 100.0,
        loss_s=round(failsafe.companion_loss * rate, 1),
        heartbeat_s=m.config.heartbeat_period * rate,
        fence_now=fence is None or fence.home_inside(),
    )
    params = ap.safety_params(needs, read)
    if isinstance(params, str):
        return _refuse(m, mode, rate, [], params)
    rows: list[dict[str, object]] = []
    wrong: list[str] = []
    for p in params:
        before = await m.link.read_param(p.name)
        if before is None:
            return _refuse(m, mode, rate, rows, f"{p.name} not readable ({p.purpose})")
        if p.accepts(before):
            rows.append(_row(p, before, before))
        elif mode == "check":
            rows.append(_row(p, before, before))
            wrong.append(f"{p.name} is {before:g}, needs {p.needed()} ({p.purpose})")
        else:
            value = p.to_write(before)
            await m.link.set_param(p.name, value, p.param_type)
            after = await m.link.read_param(p.name)
            if after is None or not p.accepts(after):
                rows.append(_row(p, before, after))
                back = "no answer" if after is None else f"{after:g}"
                why = f"{p.name} {before:g} -> {value:g} not confirmed (read back: {back})"
                return _refuse(m, mode, rate, rows, why)
            rows.append(_row(p, before, after))
            log.info("vehicle %d safety net: %s %g -> %g (%s)", v, p.name, before, after, p.purpose)
    if wrong:
        return _refuse(m, mode, rate, rows, "; ".join(wrong))
    changed = sum(1 for r in rows if r["before"] != r["after"])
    log.info(
        "vehicle %d safety net (%s): %d parameters as needed, %d changed; vehicle clock x%g",
        v,
        mode,
        len(rows),
        changed,
        rate,
    )
    m.emit("safety_net", mode=mode, state="ok", rate=rate, params=rows)
    return True


def _row(p: SafetyParam, before: float, after: float | None) -> dict[str, object]:
    def plain(x: float | None) -> float | None:
        return None if x is None or not math.isfinite(x) else round(x, 4)

    return {
        "name": p.name,
        "before": plain(before),
        "after": plain(after),
        "needed": p.needed(),
        "purpose": p.purpose,
    }


def _refuse(m: Flown, mode: str, rate: float, rows: list[dict[str, object]], why: str) -> bool:
    """Record what was read and done, say why the vehicle may not arm, end the mission."""
    v, sysid = m.config.vehicle, m.config.system_id
    line = f"vehicle {v} (system {sysid}) not armed: {why}"
    log.error("safety net (%s): %s", mode, line)
    m.emit("safety_net", mode=mode, state="refused", rate=rate, params=rows, reason=why)
    m.emit("refused", command="safety net", reason=line)
    m.request_end(f"{SAFETY_NET_REFUSED}{line}")
    return False
