"""The generated sections on the shipped OpenStreetMap extract, and their figures.

- ``osm_street_section``: docs/guide/import.md's "A real street's frontier" (the imported street's
  whole night in fast mode and 600 s at full fidelity, its coverage and blind stretches, its
  top-down picture);
- ``city_section``: docs/guide/city.md's city of the extract (its map, ranking and streets);
- ``timing_section``: docs/design/city.md's wall and CPU time with 1 and 2 workers against the target.

``street_figures`` draws their figures into docs/results/ (beside the results page, so
``make results-check`` compares them too); the pages link them as ``../results/NAME.png``.
"""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Mapping
from pathlib import Path

from citysim.config.scenario import load_scenario
from citysim.report.common import fmt_pct
from experiments.results.figures import frontier_png
from experiments.results.pages import RESULTS_COMMAND, _num, made_by, night_table
from experiments.results.sources import (
    CITY,
    CITY_90,
    CITY_TIMING,
    OSM_FULL,
    OSM_NIGHT,
    OSM_STREET,
    RESULTS_DIR,
)

#: The imported street's top-down picture, as `citysim import osm` drew it beside its scenario.
TOPDOWN_SOURCE = RESULTS_DIR.parents[1] / "scenarios" / "osm" / f"{OSM_STREET}.png"
TOPDOWN = f"osm_{OSM_STREET}_topdown.png"
NIGHT_FIGURE = f"osm_{OSM_STREET}_night.png"
FULL_FIGURE = f"osm_{OSM_STREET}_600s.png"
CITY_MAP = "city_wersten_map.png"
CITY_RANKING = "city_wersten_ranking.png"
#: The issue's targets for the city's year on 2 cores.
TARGET_WALL_S = 300.0
TARGET_SCALING = 0.8
#: Labels of the timing file's measurements (its runs two by two).
MEASUREMENTS = "ABCDEFGH"


def street_figures(out_dir: Path, results_dir: Path = RESULTS_DIR) -> list[Path]:
    """Draw (or copy) this module's figures into ``out_dir``; the paths written."""
    from citysim.report.city_map import MAP_PLOT, RANKING_PLOT, plot_map, plot_ranking

    night, full, city = OSM_NIGHT.load(results_dir), OSM_FULL.load(results_dir), CITY_90.load(results_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(TOPDOWN_SOURCE, out_dir / TOPDOWN)
    written = [out_dir / TOPDOWN,
               frontier_png(night["controllers"], f"{night['scenario']}: one whole night (fast)", out_dir / NIGHT_FIGURE),
               frontier_png(full["controllers"], f"{full['scenario']}: 600 s (full fidelity)", out_dir / FULL_FIGURE)]
    with tempfile.TemporaryDirectory() as tmp:
        for draw, drawn, name in ((plot_map, MAP_PLOT, CITY_MAP), (plot_ranking, RANKING_PLOT, CITY_RANKING)):
            draw(Path(tmp), city)
            written.append(Path(shutil.copyfile(Path(tmp) / "plots" / drawn, out_dir / name)))
    return written


def _stretches(blind: list) -> str:
    return ", ".join(f"{a:g}-{b:g}" for a, b in blind) if blind else "none"


def coverage_lines(summary: Mapping, street_length_m: float) -> list[str]:
    """What the street's cameras see (the run's coverage: lanes and sidewalks within 25 m of a
    camera, per lamp zone) and where nobody looks (stretches of s where no cell across is seen)."""
    cov, approaches = summary["coverage"], summary.get("approaches", {})
    blind = cov.get("blind_stretches_m", [])
    zones = ", ".join(f"{100 * z:.0f}" for z in cov["zone_seen"])
    return [f"The cameras see {fmt_pct(cov['street_seen'])} of the lanes and sidewalks in the lamp zones "
            f"within 25 m (per lamp zone, in order along the street: {zones} %). Blind stretches, where no "
            f"camera sees any part of the cross-section (s along the centreline, m): {_stretches(blind)}; "
            f"{sum(b - a for a, b in blind):.0f} m of the {street_length_m:.0f} m street. The street has "
            f"{_num(approaches.get('first_m'), 1)} m before its first lamp zone and "
            f"{_num(approaches.get('last_m'), 1)} m after its last ({_num(approaches.get('needed_m'), 1)} m would "
            "let the oracle light a road user entering there in time)"
            + ("; where it is shorter, even the oracle lights fewer than every entry on entry." if
               approaches.get("short_ends") else ".")]


def osm_street_section(results_dir: Path = RESULTS_DIR) -> str:
    """docs/guide/import.md's generated section: the imported street's frontier, night and 600 s."""
    night, full = OSM_NIGHT.load(results_dir), OSM_FULL.load(results_dir)
    lines = [
        f"![{night['scenario']} imported from OpenStreetMap: lamps, zones, camera views, blind stretches]"
        f"(../results/{TOPDOWN})",
        "",
        f"*The top-down picture `citysim import osm` drew beside `scenarios/osm/{OSM_STREET}.png`.*",
        "",
        *coverage_lines(night, load_scenario(TOPDOWN_SOURCE.with_suffix(".yaml")).street.length_m),
        "",
        f"### A whole night in fast mode ({night['duration_s'] / 3600:g} h, seed {night['seed']})",
        "",
        f"![Savings against lit on entry, a whole night of {night['scenario']}](../results/{NIGHT_FIGURE})",
        "",
        *night_table(night),
        "",
        made_by(OSM_NIGHT),
        "",
        f"### {full['duration_s']:g} s at full fidelity (seed {full['seed']})",
        "",
        f"![Savings against lit on entry, {full['duration_s']:g} s of {full['scenario']}](../results/{FULL_FIGURE})",
        "",
        *night_table(full),
        "",
        made_by(OSM_FULL) + f" Figures and tables drawn by `{RESULTS_COMMAND}`.",
    ]
    return "\n".join(lines)


def _money(value: float | None, currency: str) -> str:
    return "-" if value is None else f"{value:,.0f} {currency}"


def city_tables(city: Mapping) -> list[str]:
    """The ranking, then one row per street with every controller's saving and lit on entry."""
    streets = {s["name"]: s for s in city["streets"]}
    currency = city.get("currency", "")
    lines = ["| rank | street | length | lamps | road users / h at 22:00 | best controller | payback | NPV "
             "| lit on entry |", "|---|---|---|---|---|---|---|---|---|"]
    for r in city["ranking"]:
        s = streets[r["street"]]
        payback = "never" if r["payback_years"] is None else f"{r['payback_years']:.1f} years"
        lines.append(f"| {r['rank']} | {r['street']} | {s['length_m']:.0f} m | {s['lamps']} "
                     f"| {s['traffic_per_hour']:g} | {r['controller'] or 'none'} | {payback} "
                     f"| {_money(r['npv'], currency)} | {fmt_pct(r['lit_on_entry_rate'])} |")
    labels = [c for c in city["controllers"] if c != "always_on"]
    lines += ["", "| street | always-on kWh / year | " + " | ".join(f"{c}: saving, lit on entry" for c in labels) + " |",
              "|---|---|" + "---|" * len(labels)]
    for s in city["streets"]:
        cells = [f"{fmt_pct(s['controllers'][c]['savings_vs_always_on'])}, "
                 f"{fmt_pct(s['controllers'][c]['lit_on_entry_rate'])}" for c in labels]
        lines.append(f"| {s['name']} | {_num(s['controllers']['always_on']['energy_kwh_per_year'])} | "
                     + " | ".join(cells) + " |")
    return lines


def _no_best(city: Mapping) -> str:
    """Which streets have no controller lighting enough entries, with each one's best rate."""
    rows = [s for s in city["streets"] if s["best"] is None]
    if not rows:
        return f"every street has a controller lighting at least {fmt_pct(city['min_lit_on_entry'])} of entries"
    best = [max((c["lit_on_entry_rate"] or 0.0, label) for label, c in s["controllers"].items()
                if label not in ("always_on", "oracle")) for s in rows]  # fmt: skip
    return (f"{len(rows)} of {len(city['streets'])} streets have no controller other than always-on and the oracle "
            f"lighting at least {fmt_pct(city['min_lit_on_entry'])} of zone entries on entry (the most: "
            + ", ".join(f"{s['name']} {fmt_pct(rate)} with {label}" for s, (rate, label) in zip(rows, best, strict=True))
            + ")")


def _pays_back(city: Mapping) -> str:
    """How many ranked streets' best controller pays back within the hardware's lifetime."""
    life = city["money"]["lifetime_years"]
    paid = [r for r in city["ranking"] if r["payback_years"] is not None and r["payback_years"] <= life]
    ranked = [r for r in city["ranking"] if r["controller"] is not None]
    return (f"Of the {len(ranked)} streets with a best controller, {len(paid)} pay back within the hardware's "
            f"{life:g}-year lifetime at the default costs; on the others the sensors cost more than the energy "
            "they save over that lifetime (a negative NPV).") if len(paid) < len(ranked) else (
            f"Every ranked street pays back within the hardware's {life:g}-year lifetime.")


def city_section(results_dir: Path = RESULTS_DIR) -> str:
    """docs/guide/city.md's generated section: the extract's city, its map, ranking and streets."""
    city, city_90 = CITY.load(results_dir), CITY_90.load(results_dir)
    money = city["money"]
    return "\n".join([
        f"With the default `--min-lit-on-entry {city['min_lit_on_entry']:g}`, {_no_best(city)}. The map, the "
        f"ranking and the table below are the same streets' years ranked with `--min-lit-on-entry "
        f"{city_90['min_lit_on_entry']:g}`; {_no_best(city_90)}. {_pays_back(city_90)}",
        "",
        f"![{city_90['city']}: streets coloured by payback, lamps as dots](../results/{CITY_MAP})",
        "",
        f"![{city_90['city']}: streets ranked by payback](../results/{CITY_RANKING})",
        "",
        *city_tables(city_90),
        "",
        made_by(CITY) + " " + made_by(CITY_90) + f" {len(city['streets'])} streets; {city['fidelity']} fidelity, "
        f"{_num(city['sample_s'])} s per traffic level, year {city['year']}; best controller: the one paying back "
        f"first among those lighting at least the share of zone entries on entry; hardware lifetime "
        f"{money['lifetime_years']:g} years, energy {money['price_per_kwh']:g} {city.get('currency', '')}/kWh, the "
        f"default costs (see [Money](money.md)). Map and ranking drawn by `{RESULTS_COMMAND}` from the second "
        "file with `citysim city`'s own drawing.",
    ])


def _met(ok: bool) -> str:
    return "**met**" if ok else "**missed**"


def timing_section(results_dir: Path = RESULTS_DIR) -> str:
    """docs/design/city.md's generated section: wall and CPU per worker count, against the target.

    The timing file's runs are taken two by two, in order, as measurements A, B, ...: each a run
    with 1 worker and one with 2, one right after the other."""
    runs = CITY_TIMING.load(results_dir)["runs"]
    pairs = [runs[i:i + 2] for i in range(0, len(runs), 2)]
    lines = ["| measurement | workers | wall | CPU (all processes) | load average before (1, 5, 15 min) "
             "| per worker: streets in order, peak RSS after each |", "|---|---|---|---|---|---|"]
    for label, pair in zip(MEASUREMENTS, pairs, strict=False):  # more labels than pairs
        for run in pair:
            load = ", ".join(f"{x:.1f}" for x in run["load_average_1_5_15_min_before"] or []) or "-"
            workers = "; ".join(f"worker {w['worker']}: " + ", ".join(f"{s['street']} {s['peak_rss_mb']:.0f} MB"
                                                                      for s in w["streets"]) for w in run["per_worker"])
            lines.append(f"| {label} | {run['workers']} | {run['wall_s']:.1f} s | {run['cpu_s']:.1f} s | {load} "
                         f"| {workers} |")
    lines += ["", made_by(CITY_TIMING), ""]
    for label, pair in zip(MEASUREMENTS, pairs, strict=False):
        by_workers = {run["workers"]: run for run in pair}
        if 1 in by_workers and 2 in by_workers:
            lines += _verdicts(label, by_workers[1], by_workers[2])
    peaks = [s["peak_rss_mb"] for run in runs for w in run["per_worker"] for s in w["streets"]]
    if peaks:
        lines.append(f"- Each worker's peak RSS after each of its streets: {min(peaks):.0f}-{max(peaks):.0f} MB "
                     f"over {len(runs)} runs, whatever the number of streets it had run before.")
    return "\n".join(lines)


def _verdicts(label: str, one: Mapping, two: Mapping) -> list[str]:
    """Measurement ``label``'s lines: 2 workers' wall against the target, the speed-up, the balance bound."""
    speedup = one["wall_s"] / two["wall_s"]
    return [f"- {label}: with 2 workers the year took {two['wall_s']:.0f} s against the target of "
            f"{TARGET_WALL_S:.0f} s: {_met(two['wall_s'] <= TARGET_WALL_S)}. Speed-up from 1 to 2 workers "
            f"{speedup:.2f}x, {100 * speedup / 2:.0f} % of linear against the target of "
            f"{100 * TARGET_SCALING:.0f} %: {_met(speedup / 2 >= TARGET_SCALING)}. {_cpu_line(two)}"]


def _cpu_line(run: Mapping) -> str:
    """How far the streets' own CPU seconds let 2 workers split the work (the balance bound)."""
    per_worker = [sum(s["cpu_s"] for s in w["streets"]) for w in run["per_worker"]]
    total, busiest = sum(per_worker), max(per_worker, default=0.0)
    return (f"The streets' tasks took {total:.0f} CPU-s with {len(per_worker)} workers, the busier worker "
            f"{busiest:.0f} CPU-s: with whole cores of its own the split allows at most "
            f"{total / busiest if busiest else 0:.2f}x; the wall time above is what the shared machine gave.")
