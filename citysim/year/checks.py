"""Check nights: a few whole nights simulated dusk to dawn, set beside the table's estimate.

The table reads every hour off a handful of short runs; a check night simulates one real night
of the year (its dark span, each hour at its own traffic level) with ``run_comparison`` at full
fidelity and reports, per controller, the simulated energy, the table's energy for the same
night and their difference. The nights are spread evenly over the year. A whole night costs
what its hours cost (minutes per simulated hour on one core), so the default is none.
"""

from __future__ import annotations

import zoneinfo

from citysim.config.scenario import Scenario, override
from citysim.sim.compare import run_comparison
from citysim.year.annual import piece_energy_kwh
from citysim.year.factors import target_classes
from citysim.year.plan import YearPlan
from citysim.year.table import ResponseTable
from citysim.year.twilight import DarkSpan, hour_pieces


def chosen_nights(spans: list[DarkSpan], n: int) -> list[DarkSpan]:
    """``n`` nights spread evenly over the year (the middle of each n-th of the nights)."""
    n = min(n, len(spans))
    return [spans[int((i + 0.5) * len(spans) / n)] for i in range(n)]


def night_variant(plan: YearPlan, span: DarkSpan) -> Scenario:
    """The scenario of one whole night: from its dusk (clock hour with minutes) for its dark span,
    every class at the level of each run hour (taken at that hour's middle); no scripted agents."""
    tz = zoneinfo.ZoneInfo(plan.year.timezone)
    dusk = span.dusk_utc.astimezone(tz)
    pieces = hour_pieces(span, plan.year.timezone)
    run_hours = max(1, int(-(-span.hours // 1)))
    levels, edge, i = [], 0.0, 0
    for k in range(run_hours):
        middle = k + 0.5
        while i < len(pieces) - 1 and edge + pieces[i].hours <= middle:
            edge += pieces[i].hours
            i += 1
        levels.append(plan.level_of(pieces[i]))
    updates: dict = {"duration_s": span.hours * 3600.0, "traffic.scripted": [],
                     "start_hour": dusk.hour + dusk.minute / 60.0 + dusk.second / 3600.0}  # fmt: skip
    for name, spec in target_classes(plan.scenario).items():
        if spec.rate_per_hour > 0:
            updates[f"traffic.classes.{name}.hourly_profile"] = levels
    return override(plan.scenario, updates)


def run_check_nights(plan: YearPlan, table: ResponseTable, n: int, names: list[str] | None = None, *,
                     workers: int = 1, progress: bool = True) -> list[dict]:
    """Simulate ``n`` whole nights at full fidelity; each with its per-controller energies."""
    out = []
    for span in chosen_nights(plan.spans, n):
        summary = run_comparison(night_variant(plan, span), names, workers=workers, fidelity="full",
                                 progress=progress)  # fmt: skip
        pieces = hour_pieces(span, plan.year.timezone)
        tz = zoneinfo.ZoneInfo(plan.year.timezone)
        figures = {}
        for label, result in summary["controllers"].items():
            estimate = sum(piece_energy_kwh(table, label, p, plan.level_of(p)) for p in pieces)
            simulated = result["energy_kwh"]
            figures[label] = {"simulated_kwh": simulated, "table_kwh": estimate,
                              "difference_share": (estimate - simulated) / simulated if simulated else None,
                              "zone_entries": result["zone_entries"]}  # fmt: skip
        out.append({"night": span.night.isoformat(), "dusk": span.dusk_utc.astimezone(tz).isoformat(),
                    "dawn": span.dawn_utc.astimezone(tz).isoformat(), "dark_hours": span.hours,
                    "controllers": figures})  # fmt: skip
    return out
