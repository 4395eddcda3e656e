"""Scenario schema for `citysim year`: the site, its clock, the money and carbon of a kWh,
and how traffic changes over the week and the year.

One optional section, ``year:``, of a scenario. The site (latitude, longitude, IANA time
zone) fixes each night's dark span from civil dusk to civil dawn. Traffic in a dark hour is
the scenario's own hourly rates (its ``hourly_profile`` from ``start_hour`` on, and
``evening_profile`` below for the hours before ``start_hour``) times the weekday factor of
that hour's date times its month's factor, unless an hourly counts file says otherwise.
The table settings (traffic levels, sample and warm-up lengths) trade run time against
how steady the annual figures are; the defaults are measured (docs/design/year-response-table.md).
"""

from __future__ import annotations

import zoneinfo

from pydantic import Field, field_validator

from citysim.config.base import Spec

WEEKDAYS = ("mon", "tue", "wed", "thu", "fri", "sat", "sun")


class YearSpec(Spec):
    """Where the street is, what a kWh costs, and how traffic varies over the week and year."""

    latitude_deg: float = Field(ge=-90, le=90, description="site latitude, north positive")
    longitude_deg: float = Field(ge=-180, le=180, description="site longitude, east positive")
    timezone: str = Field(min_length=1, description="IANA time zone of the site's clocks, e.g. Europe/Berlin")
    year: int = Field(default=2025, ge=1900, le=2200, description="calendar year to sum over")
    tariff_per_kwh: float = Field(default=0.0, ge=0, le=100, description="energy price, currency per kWh")
    currency: str = Field(default="EUR", min_length=1, max_length=8)
    grid_kg_co2_per_kwh: float = Field(default=0.0, ge=0, le=5, description="grid emission factor, kg CO2 per kWh")
    lit_width_m: float | None = Field(
        default=None, gt=0, le=200,
        description="width of the area the lamps light (AECI); default: kerb of one sidewalk to the "
        "far edge of the other (outermost lane or sidewalk edges)",
    )  # fmt: skip
    weekday_factors: tuple[float, ...] = Field(
        default=(1.0,) * 7, description="traffic multiplier per weekday of the hour's date, Monday first"
    )
    monthly_factors: tuple[float, ...] = Field(
        default=(1.0,) * 12, description="traffic multiplier per month, January first"
    )
    evening_profile: tuple[float, ...] = Field(
        default=(1.0,),
        description="traffic multiplier (of rate_per_hour) for the dark hours before start_hour: "
        "[0] the hour just before, [1] the one before that, ...; the last value holds",
    )
    traffic_levels: tuple[float, ...] = Field(
        default=(0.5, 1.0, 2.0),
        description="traffic levels (multiples of every rate_per_hour) simulated for the response "
        "table; level 0 (nobody) is always added",
    )
    sample_s: float = Field(default=900.0, ge=30, le=14400, description="simulated seconds measured per level")
    warmup_s: float | None = Field(
        default=None, ge=0, le=3600,
        description="seconds simulated before measuring, so the street fills first; default: the "
        "street's length at 1.3 m/s (a walker's time end to end)",
    )  # fmt: skip
    idle_sample_s: float = Field(
        default=60.0, ge=10, le=3600,
        description="simulated seconds per dark clock hour with nobody about (lamps by the clock)",
    )

    @field_validator("timezone")
    @classmethod
    def _known_zone(cls, v: str) -> str:
        try:
            zoneinfo.ZoneInfo(v)
        except (zoneinfo.ZoneInfoNotFoundError, ValueError):
            import difflib

            near = difflib.get_close_matches(v, sorted(zoneinfo.available_timezones()), n=3)
            hint = f"; nearest: {', '.join(near)}" if near else ""
            raise ValueError(f"unknown IANA time zone {v!r}, e.g. Europe/Berlin{hint}") from None
        return v

    @field_validator("weekday_factors")
    @classmethod
    def _seven(cls, v: tuple[float, ...]) -> tuple[float, ...]:
        return _factors(v, 7, "Monday first")

    @field_validator("monthly_factors")
    @classmethod
    def _twelve(cls, v: tuple[float, ...]) -> tuple[float, ...]:
        return _factors(v, 12, "January first")

    @field_validator("evening_profile")
    @classmethod
    def _evening(cls, v: tuple[float, ...]) -> tuple[float, ...]:
        return _factors(v, None, "the hour before start_hour first")

    @field_validator("traffic_levels")
    @classmethod
    def _levels(cls, v: tuple[float, ...]) -> tuple[float, ...]:
        _factors(v, None, "e.g. [0.25, 0.5, 1, 2]")
        if any(x <= 0 for x in v) or len(set(v)) != len(v):
            raise ValueError(f"give distinct levels > 0 (0 is always added), got {list(v)}")
        return tuple(sorted(v))


def _factors(v: tuple[float, ...], count: int | None, order: str) -> tuple[float, ...]:
    if count is not None and len(v) != count:
        raise ValueError(f"give {count} multipliers ({order}), got {len(v)}")
    if not v:
        raise ValueError(f"give at least one multiplier ({order})")
    bad = [x for x in v if not 0 <= x <= 100]
    if bad:
        raise ValueError(f"multipliers must lie within 0..100, got {bad[0]:g}")
    return v
