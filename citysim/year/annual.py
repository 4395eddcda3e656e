"""Annual figures: every dark hour of the year read off the response table and summed.

A piece of dark hour ``f`` hours long at clock hour ``h`` and traffic level ``L`` uses
``f x (idle(h) + traffic(L))`` kWh, ``traffic`` interpolated between the table's levels; a
controller that reads the clock gets no lit-entry or dark figure. The AECI (EN 13201-5) is the
year's energy over the lit area, Wh/m2.

Design: docs/design/year-response-table.md
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from citysim.config.scenario import Scenario
from citysim.config.year import YearSpec
from citysim.metrics.intervals import lit_share_interval
from citysim.sim.compare import REFERENCE_CONTROLLERS
from citysim.year.table import ResponseTable
from citysim.year.twilight import HourPiece

#: Idle energies of a controller that differ between clock hours by more than this share read the clock.
CLOCK_TOLERANCE = 1e-6


def lit_area_m2(scenario: Scenario, year: YearSpec) -> tuple[float, float, float]:
    """(area m2, chain length m, lit width m) the AECI divides by."""
    zones = scenario.lamps.zones(scenario.street.length_m)
    chain_m = zones[-1][1] - zones[0][0]
    width_m = year.lit_width_m if year.lit_width_m is not None else _street_width_m(scenario)
    return chain_m * width_m, chain_m, width_m


def _street_width_m(scenario: Scenario) -> float:
    strips = [(s.y_center_m, s.width_m) for s in (*scenario.street.lanes, *scenario.street.sidewalks)]
    return max(y + w / 2 for y, w in strips) - min(y - w / 2 for y, w in strips)


def _interp(levels: list[float], values: list[float], level: float) -> float:
    """Linear in the level; past the highest level the last segment goes on."""
    if level <= levels[-1]:
        return float(np.interp(level, levels, values))
    slope = (values[-1] - values[-2]) / (levels[-1] - levels[-2])
    return values[-1] + slope * (level - levels[-1])


def _curve(table: ResponseTable, label: str, fig: str, levels: list[float]) -> Callable[[float], float]:
    """A figure per hour against the traffic level, above the idle reference hour (0 at level 0)."""
    base = table.idle[table.reference_hour][label][fig] if fig == "energy_kwh" else 0.0
    values = [0.0] + [table.levels[lv][label][fig] - base for lv in table.levels]
    return lambda x: _interp(levels, values, x)


def piece_energy_kwh(table: ResponseTable, label: str, piece: HourPiece, level: float) -> float:
    """One controller's energy in one dark-hour piece at a traffic level, kWh."""
    energy = _curve(table, label, "energy_kwh", [0.0, *table.levels])
    return piece.hours * (table.idle[piece.clock_hour][label]["energy_kwh"] + energy(level))


def level_weights(table: ResponseTable, pieces: list[tuple[HourPiece, int, float]]) -> np.ndarray:
    """Per level run, the weight its entries (or lit entries) carry in the year's sum: the year's
    total of a per-hour figure read off the levels (``_curve``) is linear in the level runs'
    values, so it is ``weights @ values``; found by reading the year off each run alone."""
    levels = [0.0, *table.levels]
    weights = np.zeros(len(table.levels))
    for k in range(len(weights)):
        unit = [0.0] * len(levels)
        unit[k + 1] = 1.0
        weights[k] = sum(piece.hours * _interp(levels, unit, level) for piece, _, level in pieces)
    return weights


def lit_on_entry_interval(table: ResponseTable, label: str, weights: np.ndarray) -> tuple[float, float] | None:
    """A 95 % interval of the year's lit-on-entry rate for ``label`` from its level runs' road users
    (``citysim.metrics.intervals``), each run weighted as the year weighs it; None without tallies."""
    tallies = [table.tallies.get(level, {}).get(label) for level in table.levels]
    if any(t is None for t in tallies):
        return None
    return lit_share_interval(list(zip(weights.tolist(), tallies, strict=True)))


def annual_figures(table: ResponseTable, pieces: list[tuple[HourPiece, int, float]], scenario: Scenario,
                   year: YearSpec) -> dict:
    """year.json's figures. ``pieces``: (hour piece, month of its night 1..12, traffic level)."""
    levels = [0.0, *table.levels]
    weights = level_weights(table, pieces)
    area_m2, chain_m, width_m = lit_area_m2(scenario, year)
    out: dict[str, dict] = {}
    for label in table.labels:
        energy, entries, lit, dark = (_curve(table, label, fig, levels)
                                      for fig in ("energy_kwh", "zone_entries", "lit_entries", "dark_s"))
        monthly = [0.0] * 12
        totals = dict.fromkeys(("zone_entries", "lit_entries", "dark_s"), 0.0)
        for piece, month, level in pieces:
            kwh = piece.hours * (table.idle[piece.clock_hour][label]["energy_kwh"] + energy(level))
            monthly[month - 1] += kwh
            totals["zone_entries"] += piece.hours * entries(level)
            totals["lit_entries"] += piece.hours * lit(level)
            totals["dark_s"] += piece.hours * dark(level)
        idles = [table.idle[h][label]["energy_kwh"] for h in table.idle]
        reads_clock = max(idles) - min(idles) > CLOCK_TOLERANCE * max(max(idles), 1e-12)
        kwh = sum(monthly)
        out[label] = {
            "energy_kwh_per_year": kwh,
            "cost_per_year": kwh * year.tariff_per_kwh,
            "co2_kg_per_year": kwh * year.grid_kg_co2_per_kwh,
            "aeci_wh_per_m2": kwh * 1000.0 / area_m2,
            # a clock-read light at the reference hour says nothing of its other hours: no figure
            "lit_on_entry_rate": None if reads_clock or not totals["zone_entries"]
            else totals["lit_entries"] / totals["zone_entries"],
            # how far the rate could be off from the table's few hundred entries alone; none for the
            # references, which light every entry by definition (the oracle given approaches): theirs
            # would only say how little traffic the table saw
            "lit_on_entry_interval_95": None if reads_clock or not totals["zone_entries"] or label in REFERENCE_CONTROLLERS
            else lit_on_entry_interval(table, label, weights),
            "zone_entries_per_year": totals["zone_entries"],
            "dark_s_per_year": None if reads_clock else totals["dark_s"],
            "monthly_energy_kwh": monthly,
            "reads_clock": reads_clock,
        }
    always_on = out.get("always_on", {}).get("energy_kwh_per_year")
    for figures in out.values():
        figures["savings_vs_always_on"] = 1.0 - figures["energy_kwh_per_year"] / always_on if always_on else None
    return {"controllers": out, "lit_area_m2": area_m2, "chain_length_m": chain_m, "lit_width_m": width_m,
            "dark_hours_per_year": sum(p.hours for p, _, _ in pieces),
            "dark_hours_above_table": sum(p.hours for p, _, lv in pieces if lv > levels[-1]),
            "mean_traffic_level": (sum(p.hours * lv for p, _, lv in pieces) / max(1e-12, sum(p.hours for p, _, _ in pieces)))}  # fmt: skip
