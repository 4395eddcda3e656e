"""Traffic level of each dark hour: how busy the street is, as a multiple of its base rates.

A level ``L`` means every road-user class arrives at ``L`` times its ``rate_per_hour``; the
response table is simulated at a few levels and read in between. The level of a dark hour
is the scenario's own rate at that clock hour (its ``hourly_profile`` counted from
``start_hour``; ``year.evening_profile`` for the hours before ``start_hour``), averaged over
the classes weighted by their base rates, times the weekday factor of the hour's date times
its month's factor. Hourly counts (``counts_csv``) replace that where they have a row.
"""

from __future__ import annotations

from citysim.config.kinds import AGENT_KINDS
from citysim.config.scenario import Scenario
from citysim.config.traffic import TrafficClassSpec
from citysim.config.year import YearSpec
from citysim.year.twilight import HourPiece

#: Clock hours before start_hour read from year.evening_profile; the rest from hourly_profile.
EVENING_HOURS = 12


def target_classes(scenario: Scenario) -> dict[str, TrafficClassSpec]:
    """The classes the lamps light for (animals are not traffic a weekday changes)."""
    return {name: scenario.traffic.classes.of(name) for name, kind in AGENT_KINDS.items() if kind.is_target}


def base_rate_per_hour(scenario: Scenario, kinds: list[str] | None = None) -> float:
    """Sum of the classes' rate_per_hour (level 1), arrivals per hour."""
    classes = target_classes(scenario)
    return sum(spec.rate_per_hour for name, spec in classes.items() if kinds is None or name in kinds)


def profile_multiplier(spec: TrafficClassSpec, clock_hour: int, start_hour: float,
                       evening_profile: tuple[float, ...]) -> float:
    """The class's rate multiplier at a clock hour (0..23)."""
    k = (clock_hour - int(start_hour)) % 24
    if k >= 24 - EVENING_HOURS:  # an hour before the scenario's night starts
        back = 24 - k - 1
        return evening_profile[min(back, len(evening_profile) - 1)]
    if not spec.hourly_profile:
        return 1.0
    return spec.hourly_profile[min(k, len(spec.hourly_profile) - 1)]


def clock_hour_level(scenario: Scenario, year: YearSpec, clock_hour: int) -> float:
    """The scenario's traffic at a clock hour on an average day, as a level (rate-weighted)."""
    classes = target_classes(scenario)
    total = base_rate_per_hour(scenario)
    if total == 0:
        return 0.0
    return sum(spec.rate_per_hour * profile_multiplier(spec, clock_hour, scenario.start_hour, year.evening_profile)
               for spec in classes.values()) / total  # fmt: skip


def day_factor(year: YearSpec, piece: HourPiece) -> float:
    """Weekday factor of the hour's date times its month's factor."""
    return year.weekday_factors[piece.date.weekday()] * year.monthly_factors[piece.date.month - 1]


def scenario_level(scenario: Scenario, year: YearSpec, piece: HourPiece) -> float:
    """The level of one dark-hour piece from the scenario's own factors."""
    return clock_hour_level(scenario, year, piece.clock_hour) * day_factor(year, piece)
