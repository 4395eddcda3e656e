"""Hourly traffic counts, as planners get them from traffic counters, turned into traffic levels.

The file has the header ``date_or_weekday,hour,class,count`` and one row per counted hour and
class: ``date_or_weekday`` is a date (2025-03-14) or a weekday (mon..sun, or its full name),
``hour`` the clock hour 0..23 the count starts, ``class`` a road-user class of the scenario
(pedestrian, vehicle, ...), ``count`` how many passed in that hour (>= 0). A dated row is that
hour's own count; a weekday row is a typical count for that weekday, scaled by the month's
factor. An hour's level is its counted total over the base rates (``rate_per_hour``) of the
classes counted: a counter that sees only cars sets the level of every class. Hours without
a row keep the scenario's factors. Any bad row is one ``CountsError`` naming file, line and
field, before anything is simulated.
"""

from __future__ import annotations

import csv
import datetime as dt
import difflib
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

from citysim.config.scenario import Scenario
from citysim.config.year import WEEKDAYS, YearSpec
from citysim.year.factors import base_rate_per_hour, scenario_level, target_classes
from citysim.year.twilight import HourPiece

HEADER = ["date_or_weekday", "hour", "class", "count"]
FULL_WEEKDAYS = ("monday", "tuesday", "wednesday", "thursday", "friday", "saturday", "sunday")


class CountsError(ValueError):
    """A counts file that cannot be used; the message names the file, line and field."""


@dataclass
class HourlyCounts:
    """Counts per (date, hour) and per (weekday 0..6, hour), each a {class: count} mapping."""

    source: str
    by_date: dict[tuple[dt.date, int], dict[str, float]] = field(default_factory=dict)
    by_weekday: dict[tuple[int, int], dict[str, float]] = field(default_factory=dict)

    @property
    def rows(self) -> int:
        return sum(len(v) for v in self.by_date.values()) + sum(len(v) for v in self.by_weekday.values())


def read_counts(path: str | Path, scenario: Scenario) -> HourlyCounts:
    """Read and check a counts file against the scenario's classes; raise CountsError on the first bad row."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise CountsError(f"{path}: cannot read the counts file ({exc.__class__.__name__}: {exc})") from None
    reader = csv.reader(text.splitlines())
    header = next(reader, None)
    if header is None or [h.strip().lower() for h in header] != HEADER:
        raise CountsError(f"{path}:1: the header must be {','.join(HEADER)}, got {','.join(header or [])!r}")
    counts = HourlyCounts(str(path))
    seen: set[tuple] = set()
    for line, row in enumerate(reader, start=2):
        if not row or all(not c.strip() for c in row):
            continue
        key, hour, cls, count = _parse_row(path, line, row, scenario)
        if (key, hour, cls) in seen:
            raise CountsError(f"{path}:{line}: class: {cls} at hour {hour} of {row[0].strip()} is counted twice")
        seen.add((key, hour, cls))
        table = counts.by_date if isinstance(key, dt.date) else counts.by_weekday
        table.setdefault((key, hour), {})[cls] = count
    if not seen:
        raise CountsError(f"{path}: no rows below the header; give at least one count")
    return counts


def _parse_row(path: Path, line: int, row: list[str], scenario: Scenario) -> tuple:
    where = f"{path}:{line}"
    if len(row) != len(HEADER):
        raise CountsError(f"{where}: expected {len(HEADER)} fields ({','.join(HEADER)}), got {len(row)}")
    day, hour_text, cls, count_text = (c.strip() for c in row)
    key = _day_key(where, day)
    try:
        hour = int(hour_text)
    except ValueError:
        hour = -1
    if not 0 <= hour <= 23:
        raise CountsError(f"{where}: hour: must be a whole clock hour 0..23, got {hour_text!r}")
    classes = target_classes(scenario)
    if cls not in classes:
        near = difflib.get_close_matches(cls, list(classes), n=1)
        hint = f" (nearest: {near[0]})" if near else ""
        raise CountsError(f"{where}: class: unknown {cls!r}{hint}; valid: {', '.join(classes)}")
    if classes[cls].rate_per_hour == 0:
        raise CountsError(f"{where}: class: the scenario has no {cls} traffic (rate_per_hour 0) to scale by "
                          "its counts; count another class or give it a rate")  # fmt: skip
    try:
        count = float(count_text)
    except ValueError:
        count = -1.0
    if not 0 <= count < float("inf"):
        raise CountsError(f"{where}: count: must be a number >= 0 (passages in that hour), got {count_text!r}")
    return key, hour, cls, count


def _day_key(where: str, text: str) -> dt.date | int:
    low = text.lower()
    if low in WEEKDAYS:
        return WEEKDAYS.index(low)
    if low in FULL_WEEKDAYS:
        return FULL_WEEKDAYS.index(low)
    try:
        return dt.date.fromisoformat(text)
    except ValueError:
        raise CountsError(f"{where}: date_or_weekday: give a date YYYY-MM-DD or a weekday "
                          f"({', '.join(WEEKDAYS)}), got {text!r}") from None  # fmt: skip


def counted_level(counts: HourlyCounts, scenario: Scenario, year: YearSpec, piece: HourPiece) -> float:
    """The piece's level from the counts where they have its hour, else from the scenario's factors."""
    dated = counts.by_date.get((piece.date, piece.clock_hour))
    if dated is not None:
        return _level(dated, scenario)
    typical = counts.by_weekday.get((piece.date.weekday(), piece.clock_hour))
    if typical is not None:
        return _level(typical, scenario) * year.monthly_factors[piece.date.month - 1]
    return scenario_level(scenario, year, piece)


def _level(per_class: dict[str, float], scenario: Scenario) -> float:
    return sum(per_class.values()) / base_rate_per_hour(scenario, list(per_class))


def coverage(counts: HourlyCounts, pieces: list[HourPiece]) -> dict[str, float]:
    """Dark hours whose level came from a dated row, a weekday row, or the scenario's factors."""
    hours: dict[str, float] = defaultdict(float)
    for p in pieces:
        if (p.date, p.clock_hour) in counts.by_date:
            hours["dated_rows"] += p.hours
        elif (p.date.weekday(), p.clock_hour) in counts.by_weekday:
            hours["weekday_rows"] += p.hours
        else:
            hours["scenario_factors"] += p.hours
    return {k: hours.get(k, 0.0) for k in ("dated_rows", "weekday_rows", "scenario_factors")}
