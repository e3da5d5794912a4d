"""The time-stepped engine of the swarm baselines (mdm_montecarlo.engines.social_engine), flying the
labelled reading "swarm given MDM's detection sensor" (one iteration per update
interval, the detection sensor's signal, bests of confirmed targets forgotten)."""

from __future__ import annotations

import numpy as np
import pytest

from mdm_montecarlo.engines.runner import run_missions
from mdm_montecarlo.engines.social_engine import run_swarm_block
from mdm_montecarlo.study.variants import with_method
from mdm_profiles import MissionProfile, load_profile
from mdm_profiles.overrides import apply_overrides

DETECTION_READING = (
    "policy.swarm.iteration=interval",
    "policy.swarm.signal_sensor=detection",
    "policy.swarm.after_confirmation=forget",
    "policy.swarm.read_confirmed=false",
)


def _profile(method: str, *settings: str) -> MissionProfile:
    """paper-fixed flown by a swarm method in the detection-sensor reading, simulated up to
    the 1000 s mission duration."""
    base = apply_overrides(
        load_profile("paper-fixed"), ["mission.ts_cap=1000", *DETECTION_READING, *settings]
    )
    return with_method(base, method)


def _late_repeats(per_vehicle: np.ndarray, interval: float) -> int:
    """Confirmations of a target later than one update interval after the team's first."""
    team = per_vehicle.min(axis=1, keepdims=True)
    later = np.isfinite(per_vehicle) & (per_vehicle > team + interval)
    return int(later.sum())


def test_two_workers_match_one() -> None:
    profile = _profile("SPSO", "policy.swarm.signal_radius=2000")
    one = run_missions(profile, runs=60, seed=3, workers=1, block_runs=25)
    two = run_missions(profile, runs=60, seed=3, workers=2, block_runs=25)
    assert np.array_equal(one.team_times, two.team_times)
    assert one.events == two.events
    assert np.isfinite(one.team_times).any()


def test_shared_confirmations_are_not_repeated_and_lost_ones_are() -> None:
    """With messages, a vehicle leaves a target another confirmed; with drop = 1 it does not
    know, so the same targets get confirmed again by other vehicles."""
    shared = run_swarm_block(_profile("PSO", "policy.swarm.signal_radius=2000"), 5, 0, 100)
    alone = run_swarm_block(
        _profile("PSO", "policy.swarm.signal_radius=2000", "policy.swarm.message_drop=1.0"),
        5,
        0,
        100,
    )
    confirmed = int(np.isfinite(shared.per_vehicle.min(axis=1)).sum())
    assert confirmed > 300
    # With messages, only vehicles that enter the disc in the same iteration repeat a target.
    assert _late_repeats(shared.per_vehicle, 5.0) == 0
    assert _late_repeats(alone.per_vehicle, 5.0) > 0.2 * confirmed


def test_no_messages_means_no_sharing_whatever_the_delay() -> None:
    """drop = 1: nothing arrives, so the delay cannot change a single bit (independent particles)."""
    settings = ("policy.swarm.signal_radius=2000", "policy.swarm.message_drop=1.0")
    now = run_swarm_block(_profile("ARPSO", *settings), 9, 0, 40)
    late = run_swarm_block(_profile("ARPSO", *settings, "policy.swarm.message_delay=120"), 9, 0, 40)
    assert np.array_equal(now.per_vehicle, late.per_vehicle)
    shared = run_swarm_block(_profile("ARPSO", "policy.swarm.signal_radius=2000"), 9, 0, 40)
    assert not np.array_equal(now.per_vehicle, shared.per_vehicle)


def test_sharing_helps_with_a_2km_signal() -> None:
    """Fixed seed, 200 runs: the team confirms more with messages than without."""
    shared = run_missions(_profile("PSO", "policy.swarm.signal_radius=2000"), runs=200, seed=7)
    lost = run_missions(
        _profile("PSO", "policy.swarm.signal_radius=2000", "policy.swarm.message_drop=1.0"),
        runs=200,
        seed=7,
    )
    assert shared.tnc.mean() > lost.tnc.mean() + 0.2


def test_the_three_baselines_differ_and_each_follows_shared_bests() -> None:
    """Signal read out to the detection radius r_1: PSO, SPSO and ARPSO fly
    different missions from the same random streams, and each spends a measured share of its
    iterations following a best heard from a peer (none when every message is lost)."""
    results = {m: run_missions(_profile(m), runs=100, seed=2024) for m in ("PSO", "SPSO", "ARPSO")}
    times = [r.team_times for r in results.values()]
    for i in range(3):
        for j in range(i + 1, 3):
            assert not np.array_equal(times[i], times[j])
    for method, res in results.items():
        share = res.follow_share
        assert share is not None
        print(f"{method}: T_nc {res.tnc.mean():.3f}, follows a peer's best {share:.1%}")
        assert 0.2 < share < 1.0, (method, share)
        alone = run_missions(_profile(method, "policy.swarm.message_drop=1"), runs=20, seed=2024)
        assert alone.follow_share == 0.0
    # PSO and ARPSO draw the same numbers; only ARPSO's adaptive inertia separates them.
    assert results["PSO"].tnc.mean() != pytest.approx(results["ARPSO"].tnc.mean(), abs=1e-9)


def test_detection_signal_reaches_beyond_the_confirmation_radius() -> None:
    """Read only within r_2, a signal confirms its target at once: no best forms and the
    swarm (forgetting confirmed targets) is the uniform search. Out to r_1 (signal_sensor
    detection) the swarm climbs the signal."""
    default = run_missions(_profile("PSO"), runs=100, seed=5)
    short = run_missions(_profile("PSO", "policy.swarm.signal_radius=400"), runs=100, seed=5)
    assert default.profile.policy.swarm.signal_radius is None
    assert short.follow_share == 0.0
    assert default.tnc.mean() > short.tnc.mean() + 2.0


@pytest.mark.parametrize("scenario", ["paper-fixed", "paper-popup", "paper-dynamic"])
@pytest.mark.parametrize("method", ["PSO", "SPSO", "ARPSO"])
def test_views_of_the_own_bests_give_the_inbox_results(scenario: str, method: str) -> None:
    """Every message at once, none lost (the paper's setting): the engine reads the peers' bests
    from their own bests instead of keeping the per-receiver inbox, and skips the losses'
    draw. Every first-confirmation time, the work counts and the followed share are those of
    the inbox, bit for bit; the runs do follow peers and confirm targets."""
    profile = with_method(
        apply_overrides(
            load_profile(scenario),
            ["mission.ts_cap=1000", "mission.duration=1000", *DETECTION_READING],
        ),
        method,
    )
    fast = run_swarm_block(profile, 11, 2, 40)
    inbox = run_swarm_block(profile, 11, 2, 40, keep_inbox=True)
    assert np.array_equal(fast.per_vehicle, inbox.per_vehicle)
    assert (fast.events, fast.sim_seconds, fast.followed) == (
        inbox.events,
        inbox.sim_seconds,
        inbox.followed,
    )
    assert fast.followed is not None
    assert fast.followed > 0.1 * fast.events
    assert np.isfinite(fast.per_vehicle).sum() > 40


def test_kept_bests_of_confirmed_targets_hold_the_swarm_there() -> None:
    """after_confirmation keep (standard PSO memory) in this reading: the swarm stays on the
    2 km signal of targets already confirmed, so pop-up targets appearing elsewhere are
    found far less often than when those bests are forgotten (fixed seed, 100 runs)."""
    popup = apply_overrides(
        load_profile("paper-popup"), ["mission.ts_cap=2000", *DETECTION_READING]
    )
    forgot = run_missions(with_method(popup, "PSO"), runs=100, seed=11)
    kept = run_missions(
        with_method(apply_overrides(popup, ["policy.swarm.after_confirmation=keep"]), "PSO"),
        runs=100,
        seed=11,
    )
    print(f"pop-up PSO T_nc: forget {forgot.tnc.mean():.2f}, keep {kept.tnc.mean():.2f}")
    assert kept.tnc.mean() < forgot.tnc.mean() - 2.0
