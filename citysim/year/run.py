"""`citysim year`: the site's dark hours, their traffic levels, the response table, the annual sums.

``prepare_year`` checks everything a user gives (the scenario's ``year`` section with the
command line's overrides, the counts file) and works out the dark hours before anything is
simulated; ``run_year`` builds the table, sums the year and writes DIR/year.json (staged: an
interrupted run leaves nothing half-written). Optional check nights simulate whole nights at
full fidelity and set their energy beside the table's estimate for the same nights.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from pydantic import ValidationError

from citysim.config.base import ScenarioError, describe_validation_error
from citysim.config.scenario import Scenario
from citysim.config.year import YearSpec
from citysim.year.annual import annual_figures
from citysim.year.counts_csv import HourlyCounts, counted_level, coverage, read_counts
from citysim.year.factors import scenario_level
from citysim.year.table import build_table
from citysim.year.twilight import DarkSpan, HourPiece, dark_spans, hour_pieces
from detector.outdir import staged_output


@dataclass
class YearPlan:
    """What a year run will sum: the settings, every night's dark span and its pieces with levels."""

    scenario: Scenario
    year: YearSpec
    spans: list[DarkSpan]
    pieces: list[tuple[HourPiece, int, float]]  # (piece, month of its night, traffic level)
    counts: HourlyCounts | None

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
    pieces = []
    for span in spans:
        for piece in hour_pieces(span, year.timezone):
            level = (counted_level(counts, scenario, year, piece) if counts is not None
                     else scenario_level(scenario, year, piece))  # fmt: skip
            pieces.append((piece, span.night.month, level))
    return YearPlan(scenario, year, spans, pieces, counts)


def table_runs(plan: YearPlan) -> int:
    """How many hour-runs (comparisons of every controller) the table needs."""
    return len(plan.year.traffic_levels) + len(set(plan.dark_hours) | {int(plan.scenario.start_hour)})


def run_year(plan: YearPlan, out_dir: Path, names: list[str] | None = None, *, workers: int = 1,
             fidelity: str = "full", check_nights: int = 0, progress: bool = True,
             scenario_file: str | None = None) -> dict:
    """Build the table, sum the year, run the check nights; write out_dir/year.json; return its dict."""
    table = build_table(plan.scenario, plan.year, plan.dark_hours, names, workers=workers, fidelity=fidelity,
                        progress=progress)  # fmt: skip
    figures = annual_figures(table, plan.pieces, plan.scenario, plan.year)
    y = plan.year
    result = {
        "scenario": plan.scenario.name, "scenario_file": scenario_file,
        "site": {"latitude_deg": y.latitude_deg, "longitude_deg": y.longitude_deg, "timezone": y.timezone},
        "year": y.year, "currency": y.currency, "tariff_per_kwh": y.tariff_per_kwh,
        "grid_kg_co2_per_kwh": y.grid_kg_co2_per_kwh, "nights_with_darkness": len(plan.spans),
        "traffic_source": plan.counts.source if plan.counts else "scenario factors",
        "counted_hours": coverage(plan.counts, [p for p, _, _ in plan.pieces]) if plan.counts else None,
        "fidelity": fidelity, "hour_runs": len(table.cells), "table_wall_s": table.wall_s,
        "sample_s": y.sample_s, "idle_sample_s": y.idle_sample_s,
        "warmup_s": table.cells[0].warmup_s if table.cells else None,
        **figures, "table": table.as_dict(), "check_nights": [],
    }  # fmt: skip
    if check_nights:
        from citysim.year.checks import run_check_nights

        result["check_nights"] = run_check_nights(plan, table, check_nights, names, workers=workers,
                                                  progress=progress)  # fmt: skip
    with staged_output(out_dir) as stage:
        (stage / "year.json").write_text(json.dumps(result, indent=2))
    return result
