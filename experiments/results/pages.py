"""The results page's Markdown, written from the committed result files (no figure typed by hand).

Each table says which file it was read from and the command that made that file; each figure,
the command that drew it (`make results`).
"""

from __future__ import annotations

from collections.abc import Mapping

from citysim.report.common import fmt_pct
from citysim.report.year_section import sampled_entries
from citysim.sim.compare import ORACLE_SAVES_NOTHING_BELOW, REFERENCE_CONTROLLERS
from experiments.results.sources import NIGHT, YEAR, Source

#: The command that writes this page and its figures.
RESULTS_COMMAND = "make results"


def _degrees(value: float, positive: str, negative: str) -> str:
    return f"{abs(value):g}° {positive if value >= 0 else negative}"


def _num(value: float | None, digits: int = 0) -> str:
    return "-" if value is None else f"{value:,.{digits}f}"


def _interval(name: str, figures: Mapping) -> str:
    """The lit-on-entry rate and its 95 % interval; none for always-on and the oracle, which light
    every entry by definition."""
    rate = fmt_pct(figures.get("lit_on_entry_rate"))
    low_high = figures.get("lit_on_entry_interval_95")
    if low_high is None or name in REFERENCE_CONTROLLERS:
        return rate
    return f"{rate} ({100 * low_high[0]:.1f}-{100 * low_high[1]:.1f})"


def _share_of_oracle(saving: float | None, oracle_saving: float | None) -> str:
    """``saving`` as a share of the oracle's; '-' where the oracle saves nothing to take a share of
    (``citysim.sim.compare.ORACLE_SAVES_NOTHING_BELOW``)."""
    if saving is None or oracle_saving is None or oracle_saving < ORACLE_SAVES_NOTHING_BELOW:
        return "-"
    return f"{100 * saving / oracle_saving:.0f} %"


def made_by(source: Source) -> str:
    """The sentence under a table: where its figures come from."""
    return (f"From `experiments/results/{source.file}` ({source.what}), made by `{source.command}` "
            f"(it writes `{source.produced}`).")


def year_table(year: Mapping) -> list[str]:
    """One row per controller of a year.json: energy, money, CO2, AECI, lit on entry, darkness."""
    controllers = year["controllers"]
    oracle = controllers.get("oracle", {}).get("savings_vs_always_on")
    currency = year.get("currency", "")
    lines = [f"| controller | kWh / year | saving | of the oracle's | {currency} / year | kg CO2 / year "
             "| AECI (Wh/m²) | lit on entry (95 % interval) | dark s / year |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name, c in controllers.items():
        lines.append(
            f"| {name} | {_num(c['energy_kwh_per_year'])} | {fmt_pct(c.get('savings_vs_always_on'))} "
            f"| {_share_of_oracle(c.get('savings_vs_always_on'), oracle)} | {_num(c['cost_per_year'])} "
            f"| {_num(c['co2_kg_per_year'])} | {_num(c['aeci_wh_per_m2'])} | {_interval(name, c)} "
            f"| {_num(c.get('dark_s_per_year'))} |")
    return lines


def night_table(summary: Mapping) -> list[str]:
    """One row per controller of a run's summary.json: the planner's two axes and the darkness."""
    controllers = summary["controllers"]
    lines = ["| controller | savings | of the oracle's | lit on entry (95 % interval) | zone entries "
             "| dark s per 100 entries | unlit crossings | false on (lamp-s) |",
             "|---|---|---|---|---|---|---|---|"]
    oracle = controllers.get("oracle", {}).get("savings_vs_always_on")
    for name, c in controllers.items():
        lines.append(
            f"| {name} | {fmt_pct(c.get('savings_vs_always_on'))} "
            f"| {_share_of_oracle(c.get('savings_vs_always_on'), oracle)} | {_interval(name, c)} "
            f"| {_num(c.get('zone_entries'))} | {_num(c.get('dark_s_per_100_entries'), 1)} "
            f"| {_num(c.get('unlit_crossings'))} | {_num(c.get('false_on_time_s'))} |")
    return lines


def results_page(year: Mapping, night: Mapping, figures: Mapping[str, str]) -> str:
    """The whole results page; ``figures`` maps each figure's file name (beside the page) to its caption."""
    year_fig, night_fig = figures
    lines = [
        "# Results",
        "",
        f"Every table and figure on this page is written by `{RESULTS_COMMAND}` "
        "(`python -m experiments.results`) from result files committed in `experiments/results/`; "
        "a test fails when the page or a figure differs from what those files give. Savings are "
        "against always-on lamps on the same traffic; *of the oracle's* is that saving as a share "
        "of the perfect-knowledge bound's, so a controller above 100 % saves more than lighting "
        "everyone allows, by leaving people in the dark. See [Concepts](../concepts.md) for each figure.",
        "",
        f"## A year of {year['scenario']}",
        "",
        f"![{figures[year_fig]}]({year_fig})",
        "",
        f"*{figures[year_fig]}* Drawn by `{RESULTS_COMMAND}` from the table below.",
        "",
        *year_table(year),
        "",
        made_by(YEAR) + f" Site {_degrees(year['site']['latitude_deg'], 'N', 'S')}, "
        f"{_degrees(year['site']['longitude_deg'], 'E', 'W')} ({year['site']['timezone']}), year {year['year']}, "
        f"{_num(year['dark_hours_per_year'])} dark hours, {_num(year['lit_area_m2'])} m² lit; "
        f"{year['fidelity']} fidelity, {_num(year['sample_s'])} s per traffic level. Lit on entry and dark "
        f"seconds are read from the {sampled_entries(year):,} zone entries the table's traffic-level runs "
        "measured (the same traffic for every controller), not from a year's: read the intervals.",
        "",
        f"## A whole night of {night.get('scenario', 'suburban_night')}",
        "",
        f"![{figures[night_fig]}]({night_fig})",
        "",
        f"*{figures[night_fig]}* Drawn by `{RESULTS_COMMAND}` from the table below.",
        "",
        *night_table(night),
        "",
        made_by(NIGHT),
        "",
    ]
    return "\n".join(lines)
