"""The year section of report.html, its monthly energy plot and the terminal table of `citysim year`.

Reads DIR/year.json only (written by ``citysim.year.run``), so the report needs nothing of the
simulation. Every figure has a sentence beside it saying how to read it.
"""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from citysim.report.common import controller_color, fmt_num, fmt_pct, fmt_quantity, save  # noqa: E402
from citysim.report.wording import BELOW_FULL  # noqa: E402
from citysim.report.year_entries import FEW_ENTRIES_RULE, entries_cell, entries_of, too_few  # noqa: E402

MONTHS = ("Jan", "Feb", "Mar", "Apr", "May", "Jun", "Jul", "Aug", "Sep", "Oct", "Nov", "Dec")
MONTHLY_PLOT = "monthly_energy.png"
MONTHLY_HOWTO = (
    "Energy each controller uses in each month, kWh: one line per controller. Months with long nights "
    "sit high; the gap between always_on and a controller is its saving that month, and the oracle's "
    "line is the lowest any controller can go without leaving someone below full level."
)
TABLE_HOWTO = (
    "Per controller over the whole year: energy, its saving against always-on, cost at the scenario's "
    "tariff, CO2 at its grid factor, and the AECI (EN 13201-5's annual energy per square metre lit, "
    "Wh/m2: lower is better, and it compares streets of different sizes). Lit on entry is the share "
    "of all zone entries of the year whose lamp was already at full level; below-full s is the seconds road "
    f"users spent in a zone whose lamp was {BELOW_FULL}, summed over the year. In brackets beside lit on "
    "entry, a 95 % interval: the road users of the table's traffic-level runs resampled, so it shows how far "
    "the rate could be off from those few hundred entries alone (not the sensor model's own error); then "
    "the entries the rate is read from."
)


def read_year(folder: Path) -> dict:
    return json.loads((Path(folder) / "year.json").read_text())


def plot_year(folder: str | Path) -> list[Path]:
    """DIR/plots/monthly_energy.png from DIR/year.json; returns the paths drawn."""
    folder = Path(folder)
    result = read_year(folder)
    labels = list(result["controllers"])
    fig, ax = plt.subplots(figsize=(8, 4.2))
    for label in labels:
        kwh = result["controllers"][label]["monthly_energy_kwh"]
        ax.plot(range(12), kwh, marker="o", ms=3.5, label=label, color=controller_color(label, labels),
                lw=2.2 if label in ("always_on", "oracle") else 1.4)  # fmt: skip
    ax.set_xticks(range(12), MONTHS)
    ax.set_ylabel("energy per month (kWh)")
    ax.set_ylim(bottom=0)
    ax.set_title(f"{result['scenario']}: energy per month, {result['year']}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncols=2)
    return [save(fig, folder / "plots" / MONTHLY_PLOT)]


def _rows(result: dict) -> list[list[str]]:
    cur = result["currency"]
    rows = []
    for label, f in result["controllers"].items():
        rows.append([label, fmt_quantity(f["energy_kwh_per_year"], "kWh"), fmt_pct(f["savings_vs_always_on"]),
                     fmt_quantity(f["cost_per_year"], cur), fmt_quantity(f["co2_kg_per_year"], "kg"),
                     fmt_quantity(f["aeci_wh_per_m2"], "Wh/m2"),
                     lit_with_interval(f) + entries_cell(label, f, entries_of(result, label)),
                     fmt_num(f["dark_s_per_year"])])  # fmt: skip
    return rows


MONEY_HEAD = ["controller", "capex", "opex / year", "saved / year", "payback", "NPV", "CO2 avoided"]
#: How to read each money column, one sentence each (report.html prints them under the money table).
MONEY_HOWTO = (
    ("capex", "what fitting every pole of the street with the controller's hardware costs once "
     "(hardware plus installation per pole; always-on needs none, and the oracle cannot be bought)"),
    ("opex / year", "the hardware's yearly upkeep over all poles"),
    ("saved / year", "the first year's net saving against always-on: the energy saved at the first "
     "year's price minus the upkeep (negative: the upkeep costs more than the light it saves)"),
    ("payback", "years until the net savings (the price changing yearly as set) add up to the capex; "
     "shorter is better, and a payback longer than the hardware's lifetime means it never pays for itself"),
    ("NPV", "net present value over the hardware's lifetime: every year's net saving discounted at the "
     "discount rate, minus the capex; above 0 the investment pays, and the larger the better"),
    ("CO2 avoided", "kg CO2 not emitted over the lifetime: the energy saved a year x the grid factor x "
     "the lifetime years"),
)


#: Controllers that are no investment (by label), the money columns that do not apply to them (a
#: dash, whatever an older year.json holds) and why, said beside the table.
NO_INVESTMENT = {
    "always_on": (("payback",), "always_on is the reference every figure is measured against: it needs no "
                  "investment, so it has no payback (-)"),
    "oracle": (("capex", "opex / year", "payback", "NPV"), "The oracle is a bound (it knows where every road "
               "user is), not something one can install: no capex, upkeep, payback or NPV (-); its saved / year "
               "and CO2 avoided are the most any controller could save, before upkeep"),
    "oracle_seen": (("capex", "opex / year", "payback", "NPV"), "oracle_seen is a bound too (the oracle on what "
                    "a perfect detector in the cameras sees): no capex, upkeep, payback or NPV (-)"),
}  # fmt: skip


def money_rows(result: dict) -> list[list[str]]:
    """One row per controller of the money figures (``citysim.year.money``); [] for a year.json
    without them. A figure that does not apply (``NO_INVESTMENT``) is a dash; a payback never
    reached is 'never'."""
    cur = result["currency"]
    rows = []
    for label, f in result["controllers"].items():
        if "capex" not in f:
            return []
        payback = f["payback_years"]
        row = [label, fmt_quantity(f["capex"], cur), fmt_quantity(f["opex_per_year"], cur),
               fmt_quantity(f["money_saved_per_year"], cur), "never" if payback is None else f"{payback:.1f} y",
               fmt_quantity(f["npv"], cur), fmt_quantity(f["co2_avoided_kg_over_lifetime"], "kg")]  # fmt: skip
        for column in NO_INVESTMENT.get(label, ((), ""))[0]:
            row[MONEY_HEAD.index(column)] = "-"
        rows.append(row)
    return rows


def no_investment_notes(result: dict) -> list[str]:
    """Why the dashes in the money table: one sentence per controller of ``NO_INVESTMENT`` in it."""
    return [NO_INVESTMENT[label][1] + "." for label in result["controllers"] if label in NO_INVESTMENT]


def money_facts(result: dict) -> str:
    """One sentence: the prices, lifetime and discount rate the money figures assume."""
    m = result.get("money")
    if not m:
        return ""
    return (f"Money for {m['poles']} poles at {m['price_per_kwh']:g} {result['currency']}/kWh in the first year, "
            f"changing {100 * m['price_change_per_year']:+g} % a year, {m['kg_co2_per_kwh']:g} kg CO2/kWh, "
            f"{m['lifetime_years']} years of hardware life, discounted at {100 * m['discount_rate']:g} % a year "
            "(the scenario's costs section).")


HEAD = ["controller", "energy / year", "saving", "cost / year", "CO2 / year", "AECI", "lit on entry", "below-full s / year"]


def lit_with_interval(figures: dict) -> str:
    """'97.5 % (95.9-98.8)': the year's lit-on-entry rate and its 95 % interval, where it has one."""
    interval = figures.get("lit_on_entry_interval_95")
    rate = fmt_pct(figures["lit_on_entry_rate"])
    return rate if interval is None else f"{rate} ({100 * interval[0]:.1f}-{100 * interval[1]:.1f})"


def sampled_entries(result: dict) -> int:
    """How many zone entries the table's level runs measured (the same traffic for every controller):
    what the year's lit-on-entry rate and dark seconds are read from."""
    table, sample_s = result["table"], result["sample_s"]
    first = table["labels"][0]
    return round(sum(row[first]["zone_entries"] for row in table["levels"].values()) * sample_s / 3600.0)


def year_table(result: dict) -> str:
    """The annual figures as a plain-text table for the terminal, and what its darkness is read from."""
    rows = [HEAD, *_rows(result)]
    widths = [max(len(r[i]) for r in rows) for i in range(len(HEAD))]
    lines = ["  ".join(c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(r, widths, strict=True)))
             for r in rows]  # fmt: skip
    # a rate read off a few hundred entries cannot show a 1-3 % dark share reliably: say how few
    note = (f"lit on entry and below-full s / year are read from {sampled_entries(result):,} zone entries measured in the "
            f"table's traffic-level runs ({fmt_num(result['sample_s'])} s each); in brackets a 95 % interval from "
            "resampling their road users; a whole night in fast mode (citysim run --fidelity fast --duration "
            "28800) counts thousands")
    out = [lines[0], "-" * len(lines[0]), *lines[1:], note, *_few_entries(result)]
    money = money_rows(result)
    if money:
        rows = [MONEY_HEAD, *money]
        widths = [max(len(r[i]) for r in rows) for i in range(len(MONEY_HEAD))]
        lines = ["  ".join(c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(r, widths, strict=True)))
                 for r in rows]  # fmt: skip
        out += ["", lines[0], "-" * len(lines[0]), *lines[1:], money_facts(result), *no_investment_notes(result)]
    return "\n".join(out)


def _few_entries(result: dict) -> list[str]:
    """The warning under a year table with a rate too few entries to read (``year_entries``), or none."""
    flagged = [label for label, f in result["controllers"].items() if too_few(label, f, entries_of(result, label))]
    return [FEW_ENTRIES_RULE] if flagged else []


def _html_table(head: list[str], rows: list[list[str]]) -> str:
    out = ["<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in head) + "</tr>"]
    out += ["<tr>" + "".join(f'<td{" class=l" if i == 0 else ""}>{html.escape(c)}</td>' for i, c in enumerate(r))
            + "</tr>" for r in rows]  # fmt: skip
    return '<div class="scroll">' + "\n".join(out) + "</table></div>"


def _facts(r: dict) -> str:
    site = r["site"]
    counted = r.get("counted_hours")
    traffic = ("the scenario's hourly profiles x its weekday and monthly factors" if not counted else
               f"hourly counts from {r['traffic_source']} ({fmt_num(counted['dated_rows'])} h from dated rows, "
               f"{fmt_num(counted['weekday_rows'])} h from weekday rows, the rest from the scenario's factors)")
    return (f"<p>Site {site['latitude_deg']:g}, {site['longitude_deg']:g} ({html.escape(site['timezone'])}), "
            f"{r['year']}: {r['nights_with_darkness']} nights with civil darkness, "
            f"{fmt_num(r['dark_hours_per_year'])} dark hours (civil dusk to civil dawn). Traffic: "
            f"{html.escape(traffic)}; mean level {fmt_num(r['mean_traffic_level'])} x the scenario's "
            f"rate_per_hour. Lit area {fmt_num(r['lit_area_m2'])} m2 ({fmt_num(r['chain_length_m'])} m of lamp "
            f"chain x {fmt_num(r['lit_width_m'])} m). The figures are read off {r['hour_runs']} simulated "
            f"hour-runs at {html.escape(r['fidelity'])} fidelity ({fmt_num(r['sample_s'])} s measured per "
            f"traffic level after {fmt_num(r['warmup_s'])} s of warm-up, {fmt_num(r['idle_sample_s'])} s per "
            f"idle clock hour), not simulated night by night.</p>")  # fmt: skip


def _checks(r: dict) -> str:
    if not r.get("check_nights"):
        return ""
    rows = [[c["night"], label, fmt_quantity(f["simulated_kwh"], "kWh"), fmt_quantity(f["table_kwh"], "kWh"),
             fmt_pct(f["difference_share"])]
            for c in r["check_nights"] for label, f in c["controllers"].items()]  # fmt: skip
    return ("<h3>Check nights</h3><p class='howto'>Whole nights simulated dusk to dawn at full fidelity beside "
            "the table's estimate of the same night: the difference is how far the table's shortcut "
            "(short samples, levels read in between) is off for that night.</p>"
            + _html_table(["night", "controller", "simulated", "table", "table - simulated"], rows))


def year_section(folder: str | Path) -> str:
    """The year section's HTML (table, monthly plot with its sentence, check nights); '' without year.json."""
    folder = Path(folder)
    if not (folder / "year.json").exists():
        return ""
    r = read_year(folder)
    plot = folder / "plots" / MONTHLY_PLOT
    if not plot.exists():
        plot_year(folder)
    clocked = [label for label, f in r["controllers"].items() if f.get("reads_clock")]
    note = (f"<p class='note'>Lit by the clock: {html.escape(', '.join(clocked))}. The short samples show "
            "their light at one hour only, so they get no lit-on-entry or dark figure here.</p>" if clocked else "")
    above = r.get("dark_hours_above_table") or 0
    if above:
        note += (f"<p class='note'>{fmt_num(above)} dark hours were busier than the table's highest traffic "
                 "level; their figures extend the table's last segment.</p>")
    data = base64.b64encode(plot.read_bytes()).decode("ascii")
    figure = (f'<figure id="fig-monthly_energy"><img alt="{MONTHLY_PLOT}" src="data:image/png;base64,{data}">'
              f"<figcaption><b>Energy per month.</b> {html.escape(MONTHLY_HOWTO)} "
              f'<span class="file">(plots/{MONTHLY_PLOT})</span></figcaption></figure>')
    note += "".join(f"<p class='note'>{html.escape(line)}</p>" for line in _few_entries(r))
    return ("<h2>A year</h2>" + _facts(r) + _html_table(HEAD, _rows(r))
            + f"<p class='howto'>{html.escape(TABLE_HOWTO)}</p>" + note + _money(r) + figure + _checks(r))


def _money(r: dict) -> str:
    rows = money_rows(r)
    if not rows:
        return ""
    howto = "".join(f"<li><b>{html.escape(col)}</b>: {html.escape(text)}.</li>" for col, text in MONEY_HOWTO)
    return ("<h3>Money against always-on</h3>" + _html_table(MONEY_HEAD, rows)
            + f"<p class='howto'>{html.escape(' '.join([money_facts(r), *no_investment_notes(r)]))}</p>"
            + f"<ul class='howto'>{howto}</ul>")
