"""The fence watch reads the GPS position, not the local frame the setpoints use: a vehicle whose
frame goes wrong in flight (a fault injected here: the link's offset shifted 2.5 km west) is
steered out of the fence by its own guidance, and the watch ends the search at the fence line
with the end action. Against the emulator (in this process, over UDP) with field-duebendorf."""

from __future__ import annotations

import asyncio
import re
from pathlib import Path

from companion.fly import fly
from companion.link.pymavlink_link import PymavlinkLink
from companion.mission.phase import Phase
from companion.telemetry import events
from companion.telemetry.mission_log import read_log, read_records
from mdm_profiles import load_profile
from tests.emulator_harness import free_udp_base, make_config, running_emulator
from tests.waiting import wait_until_async

_SITE = load_profile("field-duebendorf")
# The vehicle's own safety net off: GF_ACTION stays as the test sets it (below).
FIELD = _SITE.model_copy(
    update={"failsafe": _SITE.failsafe.model_copy(update={"safety_net": "off"})}
)


def test_a_wrong_frame_is_caught_at_the_fence_and_flown_home(tmp_path: Path) -> None:
    base = free_udp_base(1)

    async def main() -> str:
        link = PymavlinkLink(url=f"udpin:127.0.0.1:{base}", target_system=1)
        async with fly(
            FIELD,
            0,
            link,
            log_dir=tmp_path,
            duration=900.0,
            land_wait=300.0,
            sensor_source="virtual",
        ) as flight:
            seen = flight.mission.seen
            # 20 vehicle s into the search: the transit's northward momentum gone (its start
            # point is 20 m from the northern edge), the vehicle on a leg inside the fence
            await wait_until_async(
                lambda: (flight.mission.phase, seen.search_start, seen.clock.now),
                120.0,
                "20 vehicle s of search",
                until=lambda s: s[0] is Phase.SEARCH and s[1] is not None and s[2] >= s[1] + 20.0,
            )
            assert link.alignment is not None
            link.alignment.east -= 2500.0  # the vehicle now believes it is 2.5 km further west
            return await asyncio.wait_for(flight.ended(), 120.0)

    config = make_config(1, base, profile=FIELD, speedup=50.0, start_positions=((600.0, 1000.0),))
    with running_emulator(config) as emu:
        # The vehicle's own fence action off (GF_ACTION 0): this is about the companion's watch.
        # With PX4's stock HOLD the emulated vehicle, as a real PX4, would itself stop at the
        # line of the fence the companion uploaded, racing the watch.
        v = emu.vehicles[0]
        v.params.set("GF_ACTION", 0.0)
        v.apply_params()
        reason = asyncio.run(main())
    assert reason.startswith("outside the fence: "), reason
    records = read_records(tmp_path / "mission-0.jsonl")
    (breach,) = [r for r in records if r["event"] == "fence"]
    found = re.fullmatch(r"(\d+\.\d) m (east|north-east|south-east) of the fence", breach["where"])
    assert found, breach
    assert float(found.group(1)) < 10.0  # seen at the line (GLOBAL_POSITION_INT at 10 Hz)
    logged = read_log(tmp_path / "mission-0.jsonl")
    assert [e.phase for e in logged.of(events.PhaseChange)][-2:] == ["return", "done"]
    end = next(k for k, e in enumerate(logged.events) if isinstance(e.event, events.End))
    # RTL after the end (the PX4 persona, as PX4, then holds once landed and disarmed)
    after = logged.events[end:]
    assert "RTL" in [e.event.mode for e in after if isinstance(e.event, events.ModeChange)]
