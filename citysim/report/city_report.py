"""DIR/report.html of a city: its map and ranking, each with a sentence generated from the results.

Reads DIR/city.json only (``citysim.city.results``): nothing of the simulation is needed.
"""

from __future__ import annotations

import base64
import html
from pathlib import Path

from citysim.report.city_map import plot_map, plot_ranking, read_city
from citysim.report.common import fmt_pct, fmt_quantity
from citysim.report.html import STYLE
from citysim.report.year_section import MONEY_HOWTO


def _payback(value: float | None) -> str:
    return "never" if value is None else f"{value:.1f} years"


def map_sentence(city: dict) -> str:
    """What the map shows for this city, in one or two sentences."""
    ranked = [r for r in city["ranking"] if r["payback_years"] is not None]
    life = city["money"]["lifetime_years"]
    within = sum(1 for r in ranked if r["payback_years"] <= life)
    where = ("at their surveyed places" if city["layout"] == "origin"
             else "in a grid (the streets have no surveyed origin)")  # fmt: skip
    text = (f"The {len(city['streets'])} streets {where}, each coloured by how many years its best controller "
            f"takes to pay back (darker sooner; grey: no controller lights {fmt_pct(city['min_lit_on_entry'])} of "
            f"zone entries on entry and pays back), lamps as black dots. {within} of {len(city['streets'])} streets "
            f"pay back within the hardware's {life}-year lifetime.")
    if ranked:
        first = ranked[0]
        text += (f" {first['street']} pays back soonest: {_payback(first['payback_years'])} with "
                 f"{first['controller']}.")
    return text


def ranking_sentence(city: dict) -> str:
    """How to read the ranking, with its first and last street."""
    r = city["ranking"]
    text = (f"Streets ranked by the payback of their best controller (the one that lights at least "
            f"{fmt_pct(city['min_lit_on_entry'])} of zone entries on entry and pays back first), shortest first; "
            f"the dashed line is the hardware's lifetime: a bar beyond it never pays for itself. Equip from the top.")
    if len(r) > 1:
        text += (f" First {r[0]['street']} ({_payback(r[0]['payback_years'])}), last {r[-1]['street']} "
                 f"({_payback(r[-1]['payback_years'])}).")
    return text


def _figure(path: Path, caption: str, sentence: str) -> str:
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return (f'<figure><img alt="{path.name}" src="data:image/png;base64,{data}"><figcaption><b>{caption}.</b> '
            f'{html.escape(sentence)} <span class="file">(plots/{path.name})</span></figcaption></figure>')


def _table(city: dict) -> str:
    cur = city["currency"]
    head = ["rank", "street", "lamps", "best controller", "payback", "NPV", "lit on entry", "saving"]
    streets = {s["name"]: s for s in city["streets"]}
    rows = []
    for r in city["ranking"]:
        s = streets[r["street"]]
        best = s["controllers"].get(r["controller"] or "", {})
        rows.append([str(r["rank"]), r["street"], str(s["lamps"]), r["controller"] or "none",
                     _payback(r["payback_years"]), fmt_quantity(r["npv"], cur), fmt_pct(r["lit_on_entry_rate"]),
                     fmt_pct(best.get("savings_vs_always_on"))])  # fmt: skip
    out = ["<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in head) + "</tr>"]
    out += ["<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>" for row in rows]
    return '<div class="scroll">' + "\n".join(out) + "</table></div>"


def write_city_report(folder: str | Path) -> tuple[Path, list[Path]]:
    """Draw the map and ranking into DIR/plots/ and write DIR/report.html; (report path, plot paths)."""
    folder = Path(folder)
    city = read_city(folder)
    plots = [plot_map(folder, city), plot_ranking(folder, city)]
    m = city["money"]
    howto = "".join(f"<li><b>{html.escape(c)}</b>: {html.escape(t)}.</li>" for c, t in MONEY_HOWTO)
    site = city["site"]
    page = "\n".join([
        "<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
        f"<title>citysim city report: {html.escape(city['city'])}</title><style>{STYLE}</style></head><body>",
        f"<h1>citysim city report: {html.escape(city['city'])}</h1>",
        f"<p>{len(city['streets'])} streets at {site['latitude_deg']:g}, {site['longitude_deg']:g} "
        f"({html.escape(site['timezone'])}), {city['year']}, each summed over the year at "
        f"{html.escape(city['fidelity'])} fidelity. Money at {m['price_per_kwh']:g} {html.escape(city['currency'])}/kWh "
        f"(changing {100 * m['price_change_per_year']:+g} % a year), {m['lifetime_years']} years of hardware life, "
        f"discounted at {100 * m['discount_rate']:g} % a year; every figure against always-on lamps.</p>",
        _figure(plots[0], "City map", map_sentence(city)),
        _figure(plots[1], "Ranking", ranking_sentence(city)),
        "<h2>Ranking</h2>", _table(city), f"<ul class='howto'>{howto}</ul>",
        "<p><small>Per street and controller: city.json and city.csv beside this page; each street's year: "
        "streets/NAME/year.json.</small></p>", "</body></html>",
    ])  # fmt: skip
    path = folder / "report.html"
    path.write_text(page)
    return path, plots
