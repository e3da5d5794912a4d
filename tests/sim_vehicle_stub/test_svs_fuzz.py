"""10k+ malformed packets at one vehicle, and a flood, while MAVSDK flies another: the flight is
unaffected (tau-lag response, no link loss) and the fuzzed vehicle's counters show every drop."""

from __future__ import annotations

import asyncio
import logging
import socket
import threading
import time
from collections import Counter

import pytest
from mavsdk.asyncio import Configuration, Mavsdk
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.offboard import OffboardAsync, VelocityNedYaw
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync

from sim_vehicle_stub.framing import FrameDecoder, LinkStats
from sim_vehicle_stub.fuzz import malformed_corpus
from tests.emulator_harness import (
    TAU,
    Client,
    fitted_tau,
    free_udp_base,
    make_config,
    running_emulator,
)

log = logging.getLogger(__name__)
N_MALFORMED = 12_000
N_FLOOD = 4_000


def test_corpus_parser_rejects_every_datagram() -> None:
    stats = LinkStats()
    decoder = FrameDecoder(stats)
    corpus = malformed_corpus(3000, seed=7, target=2)
    accepted = [kind for kind, data in corpus if decoder.feed(data)]
    assert accepted == []
    assert stats.rejected_datagrams == len(corpus)
    assert min(stats.bad_crc, stats.truncated, stats.unknown_id, stats.garbage) > 0
    assert stats.malformed > 0


@pytest.mark.timeout(120)
def test_fuzzing_one_vehicle_does_not_disturb_a_mavsdk_flight_on_another() -> None:
    base = free_udp_base(2)
    cfg = make_config(2, base, speedup=10.0, flood_rate=4000.0)
    corpus = malformed_corpus(N_MALFORMED, seed=1, target=2)
    kinds = Counter(kind for kind, _ in corpus)
    samples: list[tuple[float, float]] = []

    with running_emulator(cfg) as emu:
        port = emu.local_port(1)
        sent = {"malformed": 0, "flood": 0}
        go = threading.Event()

        def fuzz() -> None:
            go.wait(30)
            with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
                for k, (_, data) in enumerate(corpus):
                    sock.sendto(data, ("127.0.0.1", port))
                    sent["malformed"] += 1
                    if k % 50 == 49:
                        time.sleep(0.02)  # ~2500/s, under the flood limit: parsed
                flood = corpus[0][1]
                for k in range(N_FLOOD):
                    sock.sendto(flood, ("127.0.0.1", port))
                    sent["flood"] += 1
                    if k % 20 == 19:
                        time.sleep(0.001)  # ~15k/s: over the limit, but not over the kernel

        fuzzer = threading.Thread(target=fuzz, daemon=True)
        fuzzer.start()

        async def fly() -> bool:
            async with Mavsdk(Configuration.create_manual(245, 190, True)) as mavsdk:
                await mavsdk.add_any_connection(f"udpin://127.0.0.1:{base}")
                system = await mavsdk.first_autopilot(timeout_s=20)
                assert system is not None
                tel, act, off = TelemetryAsync(system), ActionAsync(system), OffboardAsync(system)
                await act.set_takeoff_altitude(10.0)
                await act.arm()
                go.set()
                await act.takeoff()
                async for pos in tel.subscribe_position():
                    if pos.relative_altitude_m > 9.7:
                        break
                await off.set_velocity_ned(VelocityNedYaw(0.0, 0.0, 0.0, 0.0))
                await off.start()
                while fuzzer.is_alive():
                    # Start every step from rest, however slowly a loaded machine gets there.
                    await off.set_velocity_ned(VelocityNedYaw(0.0, 0.0, 0.0, 0.0))
                    end = time.monotonic() + 5.0
                    while abs(float(emu.fleet.vel[0, 0])) > 0.01 and time.monotonic() < end:
                        await asyncio.sleep(0.01)
                    samples.clear()
                    await off.set_velocity_ned(VelocityNedYaw(6.0, 0.0, 0.0, 0.0))
                    end = time.monotonic() + 0.8
                    while time.monotonic() < end:
                        samples.append((emu.clock.now, float(emu.fleet.vel[0, 0])))
                        await asyncio.sleep(0.005)
                return bool(await system.is_connected())

        connected = asyncio.run(asyncio.wait_for(fly(), 100))
        fuzzer.join(30)
        stats = emu.nodes[1].stats
        flown = emu.nodes[0].stats

        log.info("fuzzed vehicle counters: %s", stats.as_dict())
        log.info("flown vehicle counters: %s", flown.as_dict())
        # Fit from the last sample before the setpoint took effect (it arrives over UDP).
        start = next((k - 1 for k in range(1, len(samples)) if samples[k][1] > 1e-3), 0)
        samples[:] = samples[start:]
        log.info("fitted tau during fuzzing: %.4f s", fitted_tau(samples, 6.0))
        assert connected
        assert sent == {"malformed": N_MALFORMED, "flood": N_FLOOD}
        # The flight: a velocity step during the fuzzing still follows the tau-lag model.
        assert samples[-1][1] == pytest.approx(6.0, abs=0.05)
        assert fitted_tau(samples, 6.0) == pytest.approx(TAU, abs=0.02)
        assert flown.dropped == 0
        assert emu.vehicles[0].mode.name == "OFFBOARD"
        # The fuzzed vehicle: every malformed datagram counted as rejected or flood-dropped,
        # the flood shows up, and nothing it carried was executed.
        assert stats.rejected_datagrams + stats.flood_dropped >= N_MALFORMED
        assert stats.flood_dropped > 0
        assert stats.bad_crc > 0
        assert stats.unknown_id > 0
        assert stats.truncated > 0
        assert stats.garbage > 0
        assert min(kinds.values()) > 1000
        assert not emu.vehicles[1].armed
        # ...and it still answers a well-formed client afterwards.
        with Client(base + 1, 2) as c:
            assert c.pump(5, lambda m: m.get_type() == "HEARTBEAT") is not None
            assert c.command(400, 1) == 0
