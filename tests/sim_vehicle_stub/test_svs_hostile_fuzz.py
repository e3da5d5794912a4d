"""More than 10,000 hostile inputs per run (well-formed messages with nasty values from eight
rotating sockets, the reported hostile sequences, malformed datagrams) at a PX4 and an ArduPilot
vehicle, with the invariants checked after every batch: the emulator alive with no tick error,
every vehicle heartbeating at its rate, no NaN/inf in state or telemetry, no motion faster than
the persona's speed limit, a clean client's commands answered; at the end a clean client arms
and flies each fuzzed vehicle, and memory has not grown."""

from __future__ import annotations

import itertools
import logging
import math
import resource
import socket
import time
from typing import Any

import numpy as np
import pytest

from sim_vehicle_stub.emulator import Emulator
from sim_vehicle_stub.fuzz import malformed_corpus
from sim_vehicle_stub.hostile import fly_fast_frames, hostile_frames
from tests.emulator_harness import Client, free_udp_base, make_config, running_emulator
from tests.waiting import wait_until

log = logging.getLogger(__name__)
BATCHES = 12
HOSTILE_PER_BATCH = 450
"""Per fuzzed vehicle and batch."""
MALFORMED_PER_BATCH = 200
FUZZED = (0, 1)
"""PX4 and ArduPilot; vehicle 2 (PX4) is left alone."""
SPEED_PARAM = {"px4": ("MPC_XY_VEL_MAX", 1.0), "ardupilot": ("WPNAV_SPEED", 0.01)}
SPEED_SLACK = 1.05
"""Sampling of LOCAL_POSITION_NED at 10 Hz with float positions: 5 % over the limit allowed."""
RSS_GROWTH_MB = 60.0


def _rss_mb() -> float:
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _speed_limit(emu: Emulator, i: int) -> float:
    v = emu.vehicles[i]
    name, scale = SPEED_PARAM[v.persona.name]
    return v.params.spec(name).high * scale


def _state_finite(emu: Emulator) -> bool:
    f = emu.fleet
    arrays = (
        f.pos,
        f.vel,
        f.alt,
        f.vz,
        f.yaw,
        f.h_target,
        f.h_vel,
        f.v_target,
        f.v_vel,
        f.speed,
        f.climb,
        f.descent,
    )
    return all(bool(np.all(np.isfinite(a))) for a in arrays)


def _observe(emu: Emulator, clients: list[Client], wall: float) -> dict[Any, Any]:
    """Read every observer for ``wall`` s (after dropping what queued up during the batch):
    heartbeats and LOCAL_POSITION_NED per vehicle, and the sim seconds that passed."""
    for c in clients:
        while c.conn.recv_match(blocking=False) is not None:
            pass
    seen: dict[Any, Any] = {i: {"hb": 0, "local": []} for i in range(len(clients))}
    t0 = emu.clock.now
    end = time.monotonic() + wall
    while time.monotonic() < end:
        for i, c in enumerate(clients):
            m = c.conn.recv_match(blocking=False)
            while m is not None:
                if m.get_srcSystem() == i + 1:
                    if m.get_type() == "HEARTBEAT":
                        seen[i]["hb"] += 1
                    elif m.get_type() == "LOCAL_POSITION_NED":
                        seen[i]["local"].append(m)
                m = c.conn.recv_match(blocking=False)
        time.sleep(0.005)
    seen["sim_s"] = emu.clock.now - t0
    return seen


def _settle(emu: Emulator, sent_to: dict[int, int], timeout: float = 20.0) -> None:
    """Wait until each fuzzed vehicle has read (or dropped unread) all that was sent to it, so
    the batch's own answers (a REQUEST_MESSAGE of HEARTBEAT, say) are not observed as the
    vehicle's rates."""
    wait_until(
        lambda: {
            i: emu.nodes[i].stats.datagrams + emu.nodes[i].stats.flood_dropped for i in sent_to
        },
        timeout,
        f"every datagram read or dropped of {sent_to} sent",
        until=lambda handled: all(handled[i] >= n for i, n in sent_to.items()),
        every=0.02,
    )


def _max_speed(local: list[Any]) -> float:
    top = 0.0
    for a, b in itertools.pairwise(local):
        dt = (b.time_boot_ms - a.time_boot_ms) / 1000.0
        if dt > 0:
            top = max(top, math.hypot(b.x - a.x, b.y - a.y) / dt)
    return top


def _true_speed(truth: list[tuple[float, Any]], i: int) -> float:
    top = 0.0
    for (ta, pa), (tb, pb) in itertools.pairwise(truth):
        if tb - ta > 0.05:
            top = max(top, float(np.hypot(*(pb[i] - pa[i]))) / (tb - ta))
    return top


def _telemetry_finite(local: list[Any]) -> bool:
    return all(math.isfinite(v) for m in local for v in (m.x, m.y, m.z, m.vx, m.vy, m.vz))


def _fly(c: Client, emu: Emulator, i: int) -> None:
    """A clean client takes vehicle ``i`` over: down and disarmed, armed, up, flying north."""
    v = emu.vehicles[i]
    guided = (1, 4, 0) if v.persona.name == "ardupilot" else (1, 4, 3)  # GUIDED / HOLD
    assert c.command(400, 0, 21196) == 0, v.mode.name
    assert c.pump(30.0, lambda m: m.get_type() == "EXTENDED_SYS_STATE" and m.landed_state == 1)
    assert c.command(511, 0, 0) == 0  # every stream back to its default
    for name, value in (("MDM_FENCE_MARG", 1e6), ("MDM_BAT_ENDUR", 7200.0)):
        c.set_param(name, value)
    assert c.command(176, *guided) == 0
    assert c.command(400, 1) == 0
    alt = 10.0 if v.persona.name == "ardupilot" else 488.0 + 10.0
    assert c.command(22, 0, 0, 0, 0, 0, 0, alt) == 0
    up = c.pump(30.0, lambda m: m.get_type() == "GLOBAL_POSITION_INT" and m.relative_alt > 9500)
    assert up is not None, f"vehicle {i} did not climb after the fuzzing ({v.mode.name})"
    if v.persona.name == "px4":
        c.stream(lambda: c.velocity(5.0, 0.0), 0.5)
        assert c.command(176, 1, 6, 0) == 0  # OFFBOARD
    start = float(emu.fleet.pos[i, 0]) - v.origin[0]  # LOCAL_POSITION_NED: from its boot point
    moved = c.stream_until(
        lambda: c.velocity(5.0, 0.0),
        lambda m: m.get_type() == "LOCAL_POSITION_NED" and m.x > start + 20.0,
        30.0,
    )
    assert moved is not None, f"vehicle {i} did not fly north after the fuzzing"


@pytest.mark.timeout(240)
def test_ten_thousand_hostile_inputs_with_invariants_after_every_batch() -> None:
    base = free_udp_base(3)
    cfg = make_config(3, base, personas=("px4", "ardupilot", "px4"), flood_rate=4000.0)
    n = BATCHES * HOSTILE_PER_BATCH
    hostile = {
        i: hostile_frames(n, seed=10 + i, target=i + 1, every=HOSTILE_PER_BATCH) for i in FUZZED
    }
    malformed = malformed_corpus(BATCHES * MALFORMED_PER_BATCH, seed=3, target=1)
    senders = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(9)]
    rss_before = _rss_mb()
    sent = checks = 0
    sent_to = dict.fromkeys(FUZZED, 0)
    truth: list[tuple[float, Any]] = []
    """(sim time, every vehicle's position) sampled while the batch is sent."""
    worst = dict.fromkeys(range(3), 0.0)
    try:
        with running_emulator(cfg) as emu:
            clients = [Client(base + i, i + 1) for i in range(3)]
            try:
                for c in clients:
                    assert c.pump(10.0, lambda m: m.get_type() == "HEARTBEAT") is not None
                    c.heartbeat()
                ports = {i: emu.local_port(i) for i in FUZZED}
                for batch in range(BATCHES):
                    lo, hi = batch * HOSTILE_PER_BATCH, (batch + 1) * HOSTILE_PER_BATCH
                    for k in range(lo, hi):
                        for i in FUZZED:
                            senders[k % 8].sendto(hostile[i][k], ("127.0.0.1", ports[i]))
                            sent += 1
                            sent_to[i] += 1
                        if k % 25 == 24:
                            time.sleep(0.01)  # ~5000/s over both vehicles: under the limits
                            truth.append((emu.clock.now, emu.fleet.pos.copy()))
                    for i in FUZZED:  # end the batch flying as fast as allowed
                        for data in fly_fast_frames(i + 1):
                            senders[8].sendto(data, ("127.0.0.1", ports[i]))
                            sent_to[i] += 1
                    m_lo = batch * MALFORMED_PER_BATCH
                    for _, data in malformed[m_lo : m_lo + MALFORMED_PER_BATCH]:
                        senders[8].sendto(data, ("127.0.0.1", ports[FUZZED[batch % 2]]))
                        sent += 1
                        sent_to[FUZZED[batch % 2]] += 1
                    _settle(emu, sent_to)
                    time.sleep(0.2)
                    truth.append((emu.clock.now, emu.fleet.pos.copy()))
                    seen = _observe(emu, clients, 0.6)
                    truth.append((emu.clock.now, emu.fleet.pos.copy()))
                    # --- invariants
                    assert emu.running, f"batch {batch}: the sim loop ended"
                    assert emu.stats()["tick_errors"] == 0, f"batch {batch}"
                    assert _state_finite(emu), f"batch {batch}: NaN/inf in the vehicle state"
                    for i in range(3):
                        s = seen[i]
                        interval = emu.nodes[i].schedule.interval[0]
                        # At least the scheduled rate, at most twice it (early beats on
                        # changes), one beat of slack for the window's edges.
                        sim_s = seen["sim_s"]
                        low, high = math.floor(sim_s / interval) - 1, 2 * sim_s / interval + 1
                        assert low <= s["hb"] <= high, (batch, i, s["hb"], sim_s, interval)
                        assert _telemetry_finite(s["local"]), f"batch {batch}: vehicle {i}"
                        # Observed over MAVLink, and the truth sampled during the batch.
                        speed = max(_max_speed(s["local"]), _true_speed(truth, i))
                        worst[i] = max(worst[i], speed)
                        assert speed <= _speed_limit(emu, i) * SPEED_SLACK, (batch, i, speed)
                        checks += 5
                    truth = truth[-1:]
                    for i in FUZZED:  # a clean client is still answered
                        assert clients[i].command(512, 242) == 0, f"batch {batch}: vehicle {i}"
                        checks += 1
                stats = emu.stats()
                for i in FUZZED:
                    _fly(clients[i], emu, i)
                    checks += 1
                assert _state_finite(emu)
            finally:
                for c in clients:
                    c.close()
    finally:
        for s in senders:
            s.close()
    rss_after = _rss_mb()
    totals = stats["totals"]
    log.info(
        "hostile inputs sent %d, invariant checks %d, RSS %.1f -> %.1f MB, "
        "fastest observed (m/s) %s, counters %s",
        sent,
        checks,
        rss_before,
        rss_after,
        {i: round(w, 2) for i, w in worst.items()},
        totals,
    )
    print(
        f"hostile inputs {sent}, invariant checks {checks}, RSS {rss_before:.1f} -> "
        f"{rss_after:.1f} MB, fastest {worst}, flood_dropped {totals['flood_dropped']}, "
        f"rejected {totals['rejected_datagrams']}, nacks {totals['nacks']}"
    )
    assert sent >= 10_000
    assert totals["flood_dropped"] < sent // 10  # the inputs were read, not dropped unread
    assert rss_after - rss_before < RSS_GROWTH_MB
