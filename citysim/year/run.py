"""`citysim year`: the response table, the annual sums, the check nights, DIR/year.json.

``run_year`` takes a ``plan.YearPlan`` (everything the user gave, checked, and the year's dark
hours with their traffic levels), builds the table, sums the year and writes DIR/year.json
(staged: an interrupted run leaves nothing half-written). Optional check nights simulate whole
nights at full fidelity and set their energy beside the table's estimate for the same nights.
"""

from __future__ import annotations

import json
from pathlib import Path

from citysim.year.annual import annual_figures
from citysim.year.checks import run_check_nights
from citysim.year.counts_csv import coverage
from citysim.year.plan import YearPlan
from citysim.year.table import build_table
from detector.outdir import staged_output


def run_year(plan: YearPlan, out_dir: Path, names: list[str] | None = None, *, workers: int = 1,
             fidelity: str = "full", check_nights: int = 0, progress: bool = True,
             scenario_file: str | None = None) -> dict:
    """Build the table, sum the year, run the check nights; write out_dir/year.json; return its dict.

    Parameters
    ----------
    plan : citysim.year.plan.YearPlan
        The checked scenario and year settings, the year's dark hours and their traffic levels.
    out_dir : pathlib.Path
        Folder for year.json (staged: an interrupted run leaves nothing half-written).
    names : list of str, optional
        Controller names; None: the scenario's list (always_on and the oracle are added).
    workers : int
        Processes for the table's runs.
    fidelity : {"full", "fast"}
        How camera controllers are judged in the table's runs.
    check_nights : int
        Whole nights also simulated at full fidelity and set beside the table's estimate.
    progress : bool
        Show progress bars (simulated seconds, rate, time left).
    scenario_file : str, optional
        The scenario's file name, recorded in year.json.

    Returns
    -------
    dict
        year.json: the site, year, tariff and grid factor, dark hours, and per controller the
        energy (kWh per year and per month), cost, CO2 (kg), AECI (Wh/m2), savings against
        always-on and lit-on-entry rate (shares 0..1) with its 95 % interval, and dark seconds
        per year (s).

    Notes
    -----
    Design: docs/design/year-response-table.md.
    """
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
        result["check_nights"] = run_check_nights(plan, table, check_nights, names, workers=workers,
                                                  progress=progress)  # fmt: skip
    with staged_output(out_dir) as stage:
        (stage / "year.json").write_text(json.dumps(result, indent=2))
    return result
