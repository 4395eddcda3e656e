"""A city's results: city.json and city.csv from the streets' year.json files, and the ranking.

Per street: its name, scenario file, lamp-chain length, lamps, traffic (the target classes'
``rate_per_hour`` summed, and the year's mean level as a multiple of it), each controller's
energy, savings, lit on entry with its 95 % interval and money (``citysim.year.money``), and its
*best* controller: of the controllers other than always-on and the oracle whose year's lit-on-entry
rate is at least ``min_lit_on_entry``, the one with the shortest payback (then the largest NPV,
then the name). Streets are ranked by their best controller's payback, shortest first; streets
whose controllers all light too few entries, or never pay back, come last (by name). Everything
written is a function of the streets' year.json and the jobs, never of timing: a resumed run
writes the same bytes.
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Sequence
from pathlib import Path

from citysim.city.layout import city_layout
from citysim.city.streets import StreetJob
from citysim.config.kinds import TARGET_KINDS

REFERENCES = ("always_on", "oracle")
#: Per controller, the figures city.json and city.csv carry (year.json's names).
FIGURES = ("energy_kwh_per_year", "savings_vs_always_on", "lit_on_entry_rate", "lit_on_entry_interval_95",
           "capex", "opex_per_year", "money_saved_per_year", "payback_years", "npv", "co2_avoided_kg_over_lifetime")


def traffic_per_hour(job: StreetJob) -> float:
    """Road users an hour at the scenario's start hour: every target class's rate_per_hour summed."""
    classes = job.scenario.traffic.classes
    return float(sum(getattr(classes, kind).rate_per_hour for kind in TARGET_KINDS))


def best_controller(controllers: dict[str, dict], min_lit_on_entry: float) -> str | None:
    """The controller that pays back first among those lighting at least ``min_lit_on_entry`` of entries."""
    fit = [(f["payback_years"], -f["npv"], label) for label, f in controllers.items()
           if label not in REFERENCES and f.get("lit_on_entry_rate") is not None
           and f["lit_on_entry_rate"] >= min_lit_on_entry and f.get("payback_years") is not None]  # fmt: skip
    return min(fit)[2] if fit else None


def street_row(job: StreetJob, year: dict, geometry: dict, min_lit_on_entry: float) -> dict:
    controllers = {label: {k: f.get(k) for k in FIGURES} for label, f in year["controllers"].items()}
    best = best_controller(controllers, min_lit_on_entry)
    return {
        "name": job.name, "scenario_file": job.source, "length_m": year["chain_length_m"],
        "street_length_m": job.scenario.street.length_m, "lamps": year["money"]["poles"],
        "traffic_per_hour": traffic_per_hour(job), "mean_traffic_level": year["mean_traffic_level"],
        "controllers": controllers, "best": best,
        "best_payback_years": controllers[best]["payback_years"] if best else None,
        "best_npv": controllers[best]["npv"] if best else None, **geometry,
    }  # fmt: skip


def ranking(rows: Sequence[dict]) -> list[dict]:
    """Streets by their best controller's payback (then NPV, then name); streets without one last."""
    def order(row):
        payback = row["best_payback_years"]
        return (payback is None, payback if payback is not None else math.inf,
                -(row["best_npv"] or 0.0), row["name"])  # fmt: skip

    return [{"rank": i + 1, "street": r["name"], "controller": r["best"], "payback_years": r["best_payback_years"],
             "npv": r["best_npv"], "lit_on_entry_rate": r["controllers"][r["best"]]["lit_on_entry_rate"] if r["best"]
             else None} for i, r in enumerate(sorted(rows, key=order))]  # fmt: skip


def city_total(values: list[float | None]) -> float | None:
    """The city's sum of one figure over its streets; None where no street has it (a bound's capex)."""
    given = [v for v in values if v is not None]
    return sum(given) if given else None


def city_result(name: str, jobs: Sequence[StreetJob], years: Sequence[dict], min_lit_on_entry: float,
                city_file: str) -> dict:  # fmt: skip
    """city.json's dict from the jobs and their streets' year.json dicts (same order)."""
    mode, geometry = city_layout([job.scenario for job in jobs])
    rows = [street_row(job, year, geo, min_lit_on_entry) for job, year, geo in zip(jobs, years, geometry, strict=True)]
    first = years[0]
    labels = list(dict.fromkeys(label for y in years for label in y["controllers"]))
    totals = {label: {k: city_total([r["controllers"][label][k] for r in rows if label in r["controllers"]])
                      for k in ("energy_kwh_per_year", "capex", "opex_per_year", "npv", "co2_avoided_kg_over_lifetime")}
              for label in labels}  # fmt: skip
    return {
        "city": name, "city_file": city_file, "site": first["site"], "year": first["year"],
        "currency": first["currency"], "fidelity": first["fidelity"], "sample_s": first["sample_s"],
        "money": {k: v for k, v in first["money"].items() if k != "poles"},
        "min_lit_on_entry": min_lit_on_entry, "controllers": labels, "layout": mode,
        "streets": rows, "ranking": ranking(rows), "totals": totals,
    }  # fmt: skip


def csv_text(result: dict) -> str:
    """city.csv: one row per street; per controller its kWh/year, savings, lit on entry and its 95 %
    interval (two columns, ``_low`` and ``_high``), capex, opex, money saved, payback, NPV and CO2
    avoided (columns ``<controller>_<figure>``); an empty cell is a figure the year has not got."""
    head = ["name", "length_m", "lamps", "traffic_per_hour", "mean_traffic_level", "best", "best_payback_years"]
    names, getters = [], []
    for label in result["controllers"]:
        for k in FIGURES:
            if k == "lit_on_entry_interval_95":
                for end, i in (("low", 0), ("high", 1)):
                    names.append(f"{label}_{k}_{end}")
                    getters.append((label, k, i))
            else:
                names.append(f"{label}_{k}")
                getters.append((label, k, None))
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(head + names)
    for row in result["streets"]:
        cells = [row[h] for h in head]
        for label, k, i in getters:
            v = row["controllers"].get(label, {}).get(k)
            cells.append(v[i] if v is not None and i is not None else v)
        w.writerow(["" if v is None else repr(v) if isinstance(v, float) else v for v in cells])
    return out.getvalue()


def write_city(out_dir: Path, result: dict) -> tuple[Path, Path]:
    """DIR/city.json and DIR/city.csv (each whole or absent); their paths."""
    from citysim.city.runner import write_atomic

    json_path, csv_path = Path(out_dir) / "city.json", Path(out_dir) / "city.csv"
    scratch = Path(out_dir) / "streets"  # a killed write leaves its temporary file there, not in DIR
    write_atomic(json_path, json.dumps(result, indent=2, sort_keys=False) + "\n", scratch)
    write_atomic(csv_path, csv_text(result), scratch)
    return json_path, csv_path
