"""Check nights: a whole night simulated at full fidelity beside the table's estimate for it."""

from __future__ import annotations

import datetime as dt

import pytest

from citysim.year.checks import chosen_nights, night_variant, run_check_nights
from citysim.year.plan import prepare_year
from citysim.year.table import build_table
from citysim.year.twilight import UTC, DarkSpan


def test_check_nights_are_spread_over_the_year(toy):
    plan = prepare_year(toy, toy.year)
    nights = chosen_nights(plan.spans, 4)
    assert [n.night.month for n in nights] == [2, 5, 8, 11]


def test_a_short_check_night_matches_the_table_for_always_on(toy):
    plan = prepare_year(toy, toy.year)
    # a 2-minute "night" from 22:59 CET, so it spans two clock hours (22 and 23)
    dusk = dt.datetime(2025, 1, 6, 21, 59, tzinfo=UTC)
    plan.spans = [DarkSpan(dt.date(2025, 1, 6), dusk, dusk + dt.timedelta(minutes=2))]
    variant = night_variant(plan, plan.spans[0])
    assert variant.start_hour == pytest.approx(22 + 59 / 60) and variant.duration_s == pytest.approx(120)
    assert variant.traffic.scripted == ()
    table = build_table(toy, toy.year, [22, 23], ["always_on"], progress=False)
    [check] = run_check_nights(plan, table, 1, ["always_on"], progress=False)
    assert check["night"] == "2025-01-06" and check["dark_hours"] == pytest.approx(1 / 30)
    a = check["controllers"]["always_on"]
    assert a["simulated_kwh"] == pytest.approx(0.120 / 30, rel=1e-9)  # two 60 W lamps for 2 minutes
    assert a["table_kwh"] == pytest.approx(a["simulated_kwh"], rel=1e-9)
    assert check["controllers"]["oracle"]["simulated_kwh"] < a["simulated_kwh"]
