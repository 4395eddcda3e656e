"""Traffic level per dark hour: the scenario's factors, and hourly counts with their checks."""

from __future__ import annotations

import datetime as dt

import pytest

from citysim.config.scenario import ScenarioError, scenario_from_mapping
from citysim.year.counts_csv import CountsError, counted_level, read_counts
from citysim.year.factors import clock_hour_level, scenario_level
from citysim.year.twilight import HourPiece
from tests.citysim.year.conftest import toy_mapping


def test_levels_follow_the_profile_from_start_hour_and_the_evening_profile_before_it(toy):
    year = toy.year.model_copy(update={"evening_profile": (1.5, 2.0)})
    # toy: pedestrians 120/h with profile [1, 0.5] from 22:00, vehicles 60/h flat: rate-weighted
    assert clock_hour_level(toy, year, 22) == pytest.approx(1.0)
    assert clock_hour_level(toy, year, 23) == pytest.approx((120 * 0.5 + 60) / 180)
    assert clock_hour_level(toy, year, 4) == pytest.approx((120 * 0.5 + 60) / 180)  # last value holds
    assert clock_hour_level(toy, year, 21) == pytest.approx(1.5)  # the hour before start_hour
    assert clock_hour_level(toy, year, 17) == pytest.approx(2.0)  # the last evening value holds


def test_weekday_and_month_factors_multiply_by_the_hours_own_date(toy):
    weekday = (1.0, 1.0, 1.0, 1.0, 1.0, 2.0, 1.0)  # Saturday busier
    monthly = (1.0,) * 11 + (0.5,)  # December quieter
    year = toy.year.model_copy(update={"weekday_factors": weekday, "monthly_factors": monthly})
    saturday_december = HourPiece(dt.date(2025, 12, 6), 22, 1.0)
    friday_january = HourPiece(dt.date(2025, 1, 3), 22, 1.0)
    assert scenario_level(toy, year, saturday_december) == pytest.approx(2.0 * 0.5)
    assert scenario_level(toy, year, friday_january) == pytest.approx(1.0)


def test_counts_set_the_level_where_they_have_a_row(tmp_path, toy):
    path = tmp_path / "counts.csv"
    path.write_text("date_or_weekday,hour,class,count\n"
                    "2025-01-03,22,vehicle,90\n"     # 90 cars against 60/h: level 1.5
                    "sat,23,pedestrian,60\n"         # 60 walkers against 120/h: level 0.5 (x month)
                    "sat,23,vehicle,30\n")           # with 30 cars: (60 + 30) / (120 + 60)
    counts = read_counts(path, toy)
    year = toy.year
    assert counted_level(counts, toy, year, HourPiece(dt.date(2025, 1, 3), 22, 1.0)) == pytest.approx(1.5)
    assert counted_level(counts, toy, year, HourPiece(dt.date(2025, 1, 4), 23, 1.0)) == pytest.approx(0.5)
    # an hour without a row keeps the scenario's factors
    piece = HourPiece(dt.date(2025, 1, 5), 23, 1.0)
    assert counted_level(counts, toy, year, piece) == pytest.approx(scenario_level(toy, year, piece))


@pytest.mark.parametrize(("body", "needles"), [
    ("date,hour,class,count\n", ["counts.csv:1", "date_or_weekday,hour,class,count"]),
    ("date_or_weekday,hour,class,count\n2025-01-03,24,vehicle,3\n", ["counts.csv:2", "hour", "0..23", "'24'"]),
    ("date_or_weekday,hour,class,count\n2025-01-03,22,vehicel,3\n", ["counts.csv:2", "class", "nearest: vehicle"]),
    ("date_or_weekday,hour,class,count\n2025-13-03,22,vehicle,3\n", ["counts.csv:2", "date_or_weekday", "mon"]),
    ("date_or_weekday,hour,class,count\nmon,22,vehicle,-1\n", ["counts.csv:2", "count", ">= 0"]),
    ("date_or_weekday,hour,class,count\nmon,22,vehicle,3\nmon,22,vehicle,4\n", ["counts.csv:3", "twice"]),
    ("date_or_weekday,hour,class,count\nmon,22,cyclist,3\n", ["counts.csv:2", "class", "no cyclist traffic"]),
    ("date_or_weekday,hour,class,count\nmon,22,vehicle\n", ["counts.csv:2", "expected 4 fields"]),
])
def test_a_bad_counts_row_is_one_error_naming_file_line_and_field(tmp_path, toy, body, needles):
    path = tmp_path / "counts.csv"
    path.write_text(body)
    with pytest.raises(CountsError) as err:
        read_counts(path, toy)
    assert all(n in str(err.value) for n in needles), str(err.value)


def test_year_fields_are_checked_with_their_path():
    with pytest.raises(ScenarioError, match=r"year\.timezone.*Europe/Berlin"):
        scenario_from_mapping(toy_mapping(timezone="Europe/Berlni"), source="toy")
    with pytest.raises(ScenarioError, match=r"year\.weekday_factors.*7 multipliers"):
        scenario_from_mapping(toy_mapping(weekday_factors=[1, 1]), source="toy")
