"""The lifecycle's connect step: the vehicle heard, the messages the mission reads streaming,
its frame's origin known, and its start position checked against the search area."""

from __future__ import annotations

import asyncio
import logging
import time

from companion.link.streams import needs
from companion.mission.flown import Flown

log = logging.getLogger(__name__)


async def connect(m: Flown) -> None:
    """Until the vehicle can be flown, or the mission ended meanwhile."""
    await _await_vehicle(m)
    if m.config.dedicated_link:
        await m.link.configure_streams()
    await _ensure_streams(m)
    await _learn_origin(m)
    await _check_start(m)


async def _await_vehicle(m: Flown) -> None:
    """Wait for the vehicle's HEARTBEAT, saying every few seconds what is heard instead."""
    period = m.config.waiting_line_period
    next_line = time.monotonic() + period
    while m.seen.heartbeat is None and m.end_reason is None:
        await m.waits.wait_changed(max(next_line - time.monotonic(), 0.0))
        if m.seen.heartbeat is not None or time.monotonic() < next_line:
            continue  # other messages of the vehicle woke us: not yet time for a line
        next_line = time.monotonic() + period
        heard = sorted(m.link.heard)
        log.warning(
            "vehicle %d: waiting on %s for system %d; heard %s%s",
            m.config.vehicle,
            m.link.describe(),
            m.config.system_id,
            f"systems {heard}" if heard else "nothing",
            " (no autopilot HEARTBEAT from it yet)" if m.config.system_id in heard else "",
        )


async def _ensure_streams(m: Flown) -> None:
    """Ask for every message the mission reads; while one is missing, say which and what
    was tried, and ask again (a vehicle still booting may not answer the first time)."""
    while m.end_reason is None:
        problems = await m.link.request_streams(needs(global_position=m.link.global_position))
        if not problems:
            return
        for line in problems:
            log.warning("vehicle %d: missing %s", m.config.vehicle, line)
        m.emit("streams", missing=problems)
        await asyncio.sleep(5.0)


async def _learn_origin(m: Flown) -> None:
    """Geo-referenced profiles: where the vehicle's local frame starts (the link shifts
    positions into the profile's frame from then on); asked again until known."""
    if m.link.alignment is None:
        m.chore(_note_own_origin(m))
        return
    while m.end_reason is None:
        missing = await m.link.learn_origin()
        origin = m.link.alignment.origin
        if missing is None and origin is not None:
            a = m.link.alignment
            m.emit(
                "frame",
                source=origin.source,
                lat=round(origin.lat, 7),
                lon=round(origin.lon, 7),
                north=round(a.north, 2),
                east=round(a.east, 2),
            )
            return
        log.warning(
            "vehicle %d: origin of its local frame unknown: %s; asking again",
            m.config.vehicle,
            missing,
        )
        await asyncio.sleep(2.0)


async def _note_own_origin(m: Flown) -> None:
    """A vehicle flown in its own frame (a profile without ``site``): once it is armed (its
    origin is set by then), where that frame starts, for the run map (a SITL booted at
    ArduCopter's default home flies in Australia, not at the profile's default origin)."""
    if not await m.waits.until(lambda: m.seen.heartbeat is not None and m.seen.heartbeat.armed):
        return
    origin = await m.link.read_origin()
    if origin is not None:
        m.emit(
            "frame",
            source="own",
            lat=round(origin[0], 7),
            lon=round(origin[1], 7),
            north=0.0,
            east=0.0,
        )


async def _check_start(m: Flown) -> None:
    """Refuse to start a vehicle (GPS position) too far outside the search area."""
    if m.watch is None:
        return
    m.seen.forget_gps()  # one taken after the origin is known: the GPS has a fix by then
    await m.waits.until(lambda: m.seen.gps is not None)
    gps = m.seen.gps
    if gps is None:
        return
    why = m.watch.start_refusal(gps.north, gps.east)
    if why is None:
        return
    refusal = (
        f"vehicle {m.config.vehicle} (system {m.config.system_id}) at "
        f"{gps.lat:.6f}, {gps.lon:.6f} is {why} of profile "
        f"{m.config.profile.name}: not starting"
    )
    log.error("%s", refusal)
    m.emit("refused", command="start", reason=refusal)
    m.request_end(f"refused: {refusal}")
