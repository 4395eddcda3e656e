"""Civil dusk and dawn against published tables, and a night cut into clock hours."""

from __future__ import annotations

import datetime as dt

import pytest

from citysim.year.twilight import civil_dusk_dawn, dark_span, dark_spans, hour_pieces

#: Published civil twilight times (begin = civil dawn, end = civil dusk), local clock, to the minute.
#: Decorah, Iowa (43.3033 N, 91.7857 W, Central Daylight Time): the U.S. Naval Observatory's
#: table for September as published by Luther College's weather pages,
#: https://faculty.luther.edu/bernatzr/DecWx/Month09/Data/srssData_09.htm (a year-independent
#: table: the times move by under a minute from year to year; checked here for 2025).
#: Tromso, Norway (69.5 N, 19.0 E, UT+1 h): the U.S. Naval Observatory's "Sun and Moon Data for
#: One Day" for 1 April 2014, as quoted on answers.com ("How many hours of daylight in north
#: Norway in April"); on 30 April 2014 it lists no civil twilight at all (white night).
PUBLISHED = [
    # (place, lat, lon, zone, date, civil dawn, civil dusk)
    ("Decorah", 43.3033, -91.7857, "America/Chicago", dt.date(2025, 9, 1), "06:02", "20:11"),
    ("Decorah", 43.3033, -91.7857, "America/Chicago", dt.date(2025, 9, 15), "06:19", "19:45"),
    ("Decorah", 43.3033, -91.7857, "America/Chicago", dt.date(2025, 9, 30), "06:36", "19:18"),
    ("Tromso", 69.5, 19.0, "Etc/GMT-1", dt.date(2014, 4, 1), "03:46", "19:53"),
]
TOLERANCE_MIN = 2.0


def _minutes(t: dt.datetime) -> float:
    return t.hour * 60 + t.minute + t.second / 60


@pytest.mark.parametrize(("place", "lat", "lon", "zone", "date", "dawn", "dusk"), PUBLISHED)
def test_civil_dusk_and_dawn_match_published_tables_within_2_minutes(place, lat, lon, zone, date, dawn, dusk):
    ours_dusk, ours_dawn = civil_dusk_dawn(lat, lon, zone, date)
    for ours, published in ((ours_dawn, dawn), (ours_dusk, dusk)):
        h, m = map(int, published.split(":"))
        assert abs(_minutes(ours) - (h * 60 + m)) <= TOLERANCE_MIN, (place, date, ours, published)


def test_a_white_night_has_no_dark_span_and_a_polar_night_is_dark_all_day():
    assert civil_dusk_dawn(69.5, 19.0, "Etc/GMT-1", dt.date(2014, 4, 30)) == (None, None)
    assert dark_span(69.5, 19.0, "Etc/GMT-1", dt.date(2014, 4, 30)) is None
    polar = dark_span(78.22, 15.65, "Arctic/Longyearbyen", dt.date(2025, 12, 21))  # Svalbard
    assert polar is not None and 23.5 < polar.hours < 24.5


def test_pieces_cut_a_night_at_clock_hours_and_keep_its_length_across_summer_time():
    # Berlin, the night of 29 to 30 March 2025: clocks go from 02:00 to 03:00
    span = dark_span(52.52, 13.405, "Europe/Berlin", dt.date(2025, 3, 29))
    pieces = hour_pieces(span, "Europe/Berlin")
    assert sum(p.hours for p in pieces) == pytest.approx(span.hours, abs=1e-9)
    hours = [p.clock_hour for p in pieces]
    assert 2 not in hours and hours[hours.index(1) + 1] == 3  # 02:00 never happens that night
    assert 0 < pieces[0].hours < 1 and 0 < pieces[-1].hours < 1  # dusk and dawn fall inside an hour
    assert all(p.hours == pytest.approx(1.0) for p in pieces[1:-1])
    # civil dusk 19:11 CET, dawn 06:10 CEST = 05:10 CET: 10 h of darkness, not the clock's 11
    assert 9.9 < span.hours < 10.1


def test_a_year_has_a_dark_span_every_night_at_mid_latitudes():
    spans = dark_spans(52.52, 13.405, "Europe/Berlin", 2025)
    assert len(spans) == 365
    total_h = sum(s.hours for s in spans)
    assert 3700 < total_h < 3900  # civil night at 52.5 N: about 10.4 h a night on average
