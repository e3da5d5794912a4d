"""The emulator's clock paces sim time from the start of its loop: time spent before it
(loading the compiled kernels) is not lag that the loop then makes up by running fast, which
a client measuring the vehicle's clock (mavlink-conformance's TIMESYNC) would see as x6.5
instead of x5."""

from __future__ import annotations

import time

from sim_vehicle_stub.sim_clock import SimClock


def test_time_before_the_restart_is_not_caught_up() -> None:
    clock = SimClock(5.0)
    time.sleep(0.4)  # built, then the loop starts later
    clock.restart()
    clock.advance(1.0)  # one sim second is 0.2 wall s at x5
    assert clock.wait_time() > 0.1
    assert clock.rebases == 0


def test_without_a_restart_the_same_delay_is_lag() -> None:
    clock = SimClock(5.0)
    time.sleep(0.4)
    clock.advance(1.0)
    assert clock.wait_time() == 0.0  # behind: the loop would run flat out to catch up
