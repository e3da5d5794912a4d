"""The battery reserve that knows the way home (companion/mission/battery_reserve.py): the
flight home's time, the drain measured in this flight, the percent it needs, and the rule a site
profile gives. Pure: no link, no clock."""

from __future__ import annotations

import pytest

from companion.mission.battery_reserve import DrainMeter, ReserveRule, percent_home, reserve_rule
from mdm_profiles import load_profile

RULE = ReserveRule(reserve=10.0, horizontal=10.0, descent=1.0)


def test_the_flight_home_is_the_way_across_then_the_way_down() -> None:
    assert RULE.seconds_home(1500.0, 40.0) == pytest.approx(150.0 + 40.0)
    assert RULE.seconds_home(0.0, 40.0) == pytest.approx(40.0)
    assert RULE.seconds_home(100.0, -0.5) == pytest.approx(10.0)  # below home: no descent


def test_land_comes_down_where_it_is() -> None:
    land = ReserveRule(reserve=10.0, horizontal=0.0, descent=2.0)
    assert land.seconds_home(5000.0, 40.0) == pytest.approx(20.0)


def test_the_drain_is_measured_from_the_first_reading_of_the_flight() -> None:
    meter = DrainMeter()
    assert meter.note(100.0, 90) == 0.0  # one reading: nothing measured yet
    assert meter.note(110.0, 90) == 0.0
    assert meter.note(150.0, 80) == pytest.approx(10 / 50)
    assert meter.note(200.0, 70) == pytest.approx(20 / 100)


def test_a_fuller_pack_starts_the_measure_again() -> None:
    meter = DrainMeter()
    meter.note(0.0, 50)
    meter.note(100.0, 40)
    assert meter.note(120.0, 95) == 0.0
    assert meter.note(220.0, 85) == pytest.approx(0.1)


def test_the_percent_home_is_rounded_up() -> None:
    # 0.2 %/s for 190 s is 38 %; a hair more is 39 %.
    assert percent_home(0.2, RULE, 1500.0, 40.0) == 38
    assert percent_home(0.2, RULE, 1501.0, 40.0) == 39
    assert percent_home(0.0, RULE, 1500.0, 40.0) == 0


def test_a_site_profile_gives_the_rule_and_a_paper_profile_none() -> None:
    field = load_profile("field-duebendorf")
    assert field.site is not None
    rtl = reserve_rule(field.site, field.fleet.speed, "rtl")
    assert rtl == ReserveRule(10.0, field.fleet.speed, 1.0)
    assert reserve_rule(field.site, field.fleet.speed, "land") == ReserveRule(10.0, 0.0, 1.0)
    own = field.site.model_copy(update={"return_speed": 5.0, "battery_reserve": 15.0})
    assert reserve_rule(own, field.fleet.speed, "rtl") == ReserveRule(15.0, 5.0, 1.0)
    off = field.site.model_copy(update={"battery_reserve": None})
    assert reserve_rule(off, field.fleet.speed, "rtl") is None
    paper = load_profile("paper-fixed")
    assert reserve_rule(paper.site, paper.fleet.speed, "rtl") is None


def test_the_way_home_is_counted_no_faster_than_the_autopilot_returns() -> None:
    rule = ReserveRule(reserve=10.0, horizontal=10.0, descent=1.5)
    slow = rule.at_most(5.0)
    assert slow.horizontal == 5.0
    assert slow.seconds_home(1000.0, 30.0) == pytest.approx(2 * 100.0 + 20.0)
    assert rule.at_most(12.0) is rule
    assert rule.at_most(None) is rule
    assert rule.at_most(0.0) is rule
    land = ReserveRule(reserve=10.0, horizontal=0.0, descent=1.5)
    assert land.at_most(5.0) is land  # LAND comes down where it is
