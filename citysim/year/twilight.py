"""Dark spans of a site's nights, civil dusk to civil dawn, cut into local clock hours.

Sun times come from ``astral`` (a maintained astronomy library; times of the sun's centre at
6 degrees below the horizon, the usual switching point of street lighting); nothing here
computes the sun's position itself. Night ``d`` runs from civil dusk on date ``d`` to civil
dawn on ``d + 1``, in the site's IANA time zone (summer time included). Near the poles a
night may have no civil darkness at all (white nights: 0 dark hours) or the sun may stay
below -6 degrees all day (the dark span then runs noon to noon).
"""

from __future__ import annotations

import datetime as dt
import zoneinfo
from dataclasses import dataclass

from astral import Observer
from astral import sun as astral_sun

UTC = dt.UTC
#: The sun's centre this far below the horizon ends evening civil twilight and starts morning's, deg.
CIVIL_DEPRESSION_DEG = 6.0


@dataclass(frozen=True)
class DarkSpan:
    """One night's darkness: civil dusk to civil dawn, aware datetimes in UTC."""

    night: dt.date
    dusk_utc: dt.datetime
    dawn_utc: dt.datetime

    @property
    def hours(self) -> float:
        return (self.dawn_utc - self.dusk_utc).total_seconds() / 3600.0


@dataclass(frozen=True)
class HourPiece:
    """The part of a dark span inside one local clock hour."""

    date: dt.date  # local calendar date of the hour
    clock_hour: int  # 0..23, local
    hours: float  # 0 < hours <= 1


def civil_dusk_dawn(latitude_deg: float, longitude_deg: float, timezone: str, date: dt.date
                    ) -> tuple[dt.datetime | None, dt.datetime | None]:
    """Civil dusk on ``date`` and civil dawn on ``date``, local aware datetimes; None when the sun
    does not cross -6 degrees that day (astral raises ValueError then)."""
    observer, tz = Observer(latitude_deg, longitude_deg), zoneinfo.ZoneInfo(timezone)
    times = []
    for event in (astral_sun.dusk, astral_sun.dawn):
        try:
            times.append(event(observer, date, depression=CIVIL_DEPRESSION_DEG, tzinfo=tz))
        except ValueError:
            times.append(None)
    return times[0], times[1]


def dark_span(latitude_deg: float, longitude_deg: float, timezone: str, night: dt.date) -> DarkSpan | None:
    """Night ``night``'s civil darkness, or None when it has none (white night)."""
    observer, tz = Observer(latitude_deg, longitude_deg), zoneinfo.ZoneInfo(timezone)
    after = night + dt.timedelta(days=1)
    dusk, _ = civil_dusk_dawn(latitude_deg, longitude_deg, timezone, night)
    _, dawn = civil_dusk_dawn(latitude_deg, longitude_deg, timezone, after)
    if dusk is not None and dawn is not None and dusk < dawn:
        return DarkSpan(night, dusk.astimezone(UTC), dawn.astimezone(UTC))
    deepest = astral_sun.midnight(observer, after, tzinfo=tz)
    if astral_sun.elevation(observer, deepest) >= -CIVIL_DEPRESSION_DEG:
        return None  # the sun never gets 6 degrees below the horizon tonight
    # polar night (or its edge): dark from noon, or from dusk if there is one, to the next noon or dawn
    start = dusk if dusk is not None else astral_sun.noon(observer, night, tzinfo=tz)
    end = dawn if dawn is not None else astral_sun.noon(observer, after, tzinfo=tz)
    return DarkSpan(night, start.astimezone(UTC), end.astimezone(UTC))


def dark_spans(latitude_deg: float, longitude_deg: float, timezone: str, year: int) -> list[DarkSpan]:
    """Every night of ``year`` that has civil darkness (the night of 31 December runs into January)."""
    day, spans = dt.date(year, 1, 1), []
    while day.year == year:
        span = dark_span(latitude_deg, longitude_deg, timezone, day)
        if span is not None:
            spans.append(span)
        day += dt.timedelta(days=1)
    return spans


def hour_pieces(span: DarkSpan, timezone: str) -> list[HourPiece]:
    """The span cut at local clock-hour boundaries; the first and last pieces are fractional.

    Cut in absolute time, so a summer-time change inside the night neither loses nor doubles an
    hour: the clock hour repeated in autumn gives two pieces with the same label."""
    tz = zoneinfo.ZoneInfo(timezone)
    pieces, t = [], span.dusk_utc
    while t < span.dawn_utc:
        local = t.astimezone(tz)
        into_hour_s = local.minute * 60 + local.second + local.microsecond / 1e6
        end = min(span.dawn_utc, t + dt.timedelta(seconds=3600.0 - into_hour_s))
        pieces.append(HourPiece(local.date(), local.hour, (end - t).total_seconds() / 3600.0))
        t = end
    return pieces
