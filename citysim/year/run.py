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
from citysim.year.money import add_money
from citysim.year.plan import YearPlan
from citysim.year.table import build_table
from detector.outdir import staged_output


def run_year(plan: YearPlan, out_dir: Path, names: list[str] | None = None, *, workers: int = 1,
             fidelity: str = "full", check_nights: int = 0, progress: bool = True,
             scenario_file: str | None = None, sensor_model=None) -> dict:
    """Build the response table, sum the year, cost it, run the check nights; write out_dir/year.json.

    Parameters
    ----------
    plan : YearPlan
        The checked input and the year's dark hours with their traffic levels (``citysim.year.plan``).
    out_dir : Path
        Folder to write year.json into (staged: an interrupted run leaves nothing half-written).
    names : list of str, optional
        Controllers (default: the scenario's list).
    workers : int
        Parallel processes for the table's runs.
    fidelity : {"full", "fast"}
        How the camera controllers are judged in the table's runs.
    check_nights : int
        Whole nights simulated at full fidelity beside the table's estimate (0: none).
    progress : bool
        Show a progress bar.
    scenario_file : str, optional
        The scenario's path, recorded in year.json.
    sensor_model : SensorModel, optional
        Fast fidelity's model to use (default: the scenario's, looked up or calibrated); a city
        passes the one it shares between streets with the same camera.

    Returns
    -------
    dict
        year.json's contents: per controller ``energy_kwh_per_year``, ``savings_vs_always_on``,
        ``cost_per_year``, ``co2_kg_per_year``, ``aeci_wh_per_m2`` (Wh/m²), ``lit_on_entry_rate``
        and its 95 % interval, ``zone_entries_per_year``, ``dark_s_per_year``, and the money against always-on
        (``capex``, ``opex_per_year``, ``money_saved_per_year``, ``payback_years``, ``npv``,
        ``co2_avoided_kg_over_lifetime``); the table and the check nights.

    Notes
    -----
    Design: docs/design/year-response-table.md.
    """
    table = build_table(plan.scenario, plan.year, plan.dark_hours, names, workers=workers, fidelity=fidelity,
                        progress=progress, sensor_model=sensor_model)  # fmt: skip
    figures = annual_figures(table, plan.pieces, plan.scenario, plan.year)
    money = add_money(figures["controllers"], plan.scenario, plan.year, names)
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
        **figures, "money": money, "table": table.as_dict(), "check_nights": [],
    }  # fmt: skip
    if check_nights:
        result["check_nights"] = run_check_nights(plan, table, check_nights, names, workers=workers,
                                                  progress=progress)  # fmt: skip
    with staged_output(out_dir) as stage:
        (stage / "year.json").write_text(json.dumps(result, indent=2))
    return result
