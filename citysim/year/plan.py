"""What a year run will sum, worked out before anything is simulated.

``year_spec`` is the scenario's ``year`` section with the command line's overrides, checked;
``prepare_year`` reads and checks the counts file and cuts every night's dark span into
clock-hour pieces, each with its traffic level.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from pydantic import ValidationError

from citysim.config.base import ScenarioError, describe_validation_error
from citysim.config.scenario import Scenario
from citysim.config.year import YearSpec
from citysim.year.counts_csv import CountsError, HourlyCounts, counted_level, coverage, read_counts
from citysim.year.factors import scenario_level
from citysim.year.table import plan_cells
from citysim.year.twilight import DarkSpan, HourPiece, dark_spans, hour_pieces


@dataclass
class YearPlan:
    """What a year run will sum: the settings, every night's dark span and its pieces with levels."""

    scenario: Scenario
    year: YearSpec
    spans: list[DarkSpan]
    pieces: list[tuple[HourPiece, int, float]]  # (piece, month of its night, traffic level)
    counts: HourlyCounts | None

    def level_of(self, piece: HourPiece) -> float:
        """The traffic level of a dark-hour piece: from the counts where they have it, else the factors."""
        if self.counts is not None:
            return counted_level(self.counts, self.scenario, self.year, piece)
        return scenario_level(self.scenario, self.year, piece)

    @property
    def dark_hours(self) -> list[int]:
        return sorted({p.clock_hour for p, _, _ in self.pieces})


def year_spec(scenario: Scenario, source: str, **overrides) -> YearSpec:
    """The scenario's ``year`` section with the given fields replaced (None: keep); errors name the field."""
    given = {k: v for k, v in overrides.items() if v is not None}
    base = scenario.year.model_dump() if scenario.year is not None else {}
    if not base and not {"latitude_deg", "longitude_deg", "timezone"} <= given.keys():
        raise ScenarioError(f"{source}: year: the scenario has no `year:` section; add one (see "
                            "scenarios/suburban_night.yaml) or give --lat, --lon and --timezone")  # fmt: skip
    try:
        return YearSpec.model_validate({**base, **given})
    except ValidationError as exc:
        raise ScenarioError(f"{source}: year.{describe_validation_error(exc, YearSpec)}") from None


def prepare_year(scenario: Scenario, year: YearSpec, counts_path: Path | None = None) -> YearPlan:
    """Counts read and checked, the year's dark spans cut into clock-hour pieces with their levels."""
    counts = read_counts(counts_path, scenario) if counts_path is not None else None
    spans = dark_spans(year.latitude_deg, year.longitude_deg, year.timezone, year.year)
    plan = YearPlan(scenario, year, spans, [], counts)
    plan.pieces = [(piece, span.night.month, plan.level_of(piece))
                   for span in spans for piece in hour_pieces(span, year.timezone)]  # fmt: skip
    if counts is not None and counts.by_date and not coverage(counts, [p for p, _, _ in plan.pieces])["dated_rows"]:
        dates = sorted(d for d, _ in counts.by_date)
        raise CountsError(f"{counts.source}: none of its dated rows ({dates[0]} .. {dates[-1]}) falls in a dark "
                          f"hour of {year.year}; give the counts' year with --year, or weekday rows")  # fmt: skip
    return plan


def table_runs(plan: YearPlan) -> tuple[int, float]:
    """How many hour-runs (comparisons of every controller) the table needs, and the seconds they
    simulate per controller (warm-ups included)."""
    cells = plan_cells(plan.scenario, plan.year, plan.dark_hours)
    return len(cells), sum(c.duration_s for c in cells)
