"""One self-contained HTML page per run or sweep folder: every plot, the figures, the best settings.

``write_report(folder)`` redraws the folder's plots (``run_plots.plot_run`` for a run
folder with summary.json, ``sweep_plots.plot_sweep`` for a sweep folder with
results.csv) unless given the ones just drawn, and writes FOLDER/report.html with each
PNG embedded as a base64 data URI, so the page opens anywhere (mail it, put it on a
share) without the plots folder. Every figure has a sentence saying what it shows and
how to read it (``captions``), and numbers are written for people (5,818 lamp-s, 34.7 %).

A run page says which clock hours the run covers and how many objects crossed (with a
warning when they are few), why a controller saves 0 % when its window is the reason,
and reads the per-frame detection figures against the crossings. A sweep page shows
the best settings per controller: the highest savings among settings where no object
crossed a zone whose lamp never reached full level (``unlit_crossings == 0``), and the lowest lag p95.
"""

from __future__ import annotations

import base64
import html
import math
from collections import defaultdict
from datetime import UTC, datetime
from pathlib import Path

from citysim.report.captions import caption_for
from citysim.report.common import (
    PlotError,
    axis_label,
    fmt_num,
    fmt_pct,
    fmt_quantity,
    slug,
    to_float,
)
from citysim.report.wording import BELOW_FULL, best_installable_sentence
from citysim.world.approaches import describe_short

__all__ = ["best_settings", "write_report"]

REFERENCE = "always_on"
STYLE = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1150px; color: #222;
       padding: 0 1em; line-height: 1.4; }
h1 { font-size: 1.5em; } h2 { font-size: 1.2em; margin-top: 1.8em; border-bottom: 1px solid #ccc; }
h3 { font-size: 1.05em; margin-top: 1.2em; }
table { border-collapse: collapse; font-size: 0.9em; margin: 0.6em 0; }
.scroll { overflow-x: auto; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.6em; text-align: right; }
td { white-space: nowrap; } th { background: #f2f2f2; vertical-align: bottom; }
td.l, th.l { text-align: left; white-space: normal; }
figure { margin: 1.6em 0; } img { max-width: 100%; border: 1px solid #eee; }
figcaption { font-size: 0.92em; color: #333; max-width: 60em; margin-top: 0.3em; }
figcaption .file { color: #888; font-size: 0.9em; }
.note { color: #8a5a00; } .howto { font-size: 0.9em; color: #444; max-width: 60em; }
.window { font-size: 1.02em; }
.warning { background: #fff3cd; border: 2px solid #b00000; color: #7a0000; padding: 0.6em 0.9em;
           font-weight: bold; max-width: 60em; }
.reason, .detection { max-width: 60em; }
"""

#: What the columns of the run table mean, shown under it.
RUN_COLUMNS_HOWTO = (
    "Lag: seconds from an object entering a lamp's zone until that lamp is at full (p50: half "
    "the entries wait less, p95: all but 5 %); entries never lit count at their whole stay. "
    "Never-full crossings: zone entries whose lamp never reached full level while the object was in the "
    f"zone. Below-full exposure: seconds objects spent in zones whose lamp was {BELOW_FULL}, summed over "
    "objects. "
    "False on-time: lamp-seconds above dim with nobody in the lamp's zone. Per-frame TPR and "
    "passes missed: the camera detector's figures (explained below the table)."
)


def _table(head: list[str], rows: list[list[str]], left: int = 1) -> str:
    def cell(tag: str, i: int, text: str) -> str:
        cls = ' class="l"' if i < left else ""
        return f"<{tag}{cls}>{html.escape(text)}</{tag}>"

    out = ["<table><tr>" + "".join(cell("th", i, h) for i, h in enumerate(head)) + "</tr>"]
    for r in rows:
        out.append("<tr>" + "".join(cell("td", i, c) for i, c in enumerate(r)) + "</tr>")
    # a wide table scrolls on its own rather than pushing the page sideways
    return '<div class="scroll">' + "\n".join(out) + "</table></div>"


def _figure(path: Path, kind: str, names: dict[str, str] | None = None) -> str:
    """The PNG embedded, with its caption: a short title, how to read it, and its file name."""
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    title, sentence = caption_for(path.name, kind, names)
    # alt is the file name (tests/citysim/sweep/test_sweep.py finds the images by it); the caption says the rest
    return (f'<figure id="fig-{html.escape(path.stem)}"><img alt="{html.escape(path.name)}" '
            f'src="data:image/png;base64,{data}">'
            f"<figcaption><b>{html.escape(title)}.</b> {html.escape(sentence)} "
            f'<span class="file">(plots/{html.escape(path.name)})</span></figcaption></figure>')  # fmt: skip


def _notes(folder: Path) -> str:
    path = folder / "plots" / "notes.txt"
    if not path.exists():
        return ""
    lines = [line for line in path.read_text().splitlines() if line.strip()]
    return "".join(f'<p class="note">{html.escape(line)}</p>' for line in lines)


def _run_rows(figures: dict) -> list[list[str]]:
    rows = []
    for name, f in figures.items():
        det = f.get("detection") or {}
        rows.append([name, fmt_quantity(f.get("energy_kwh"), "kWh"), fmt_pct(f.get("savings_vs_always_on")),
                     fmt_quantity(f.get("lag_p50_s"), "s"), fmt_quantity(f.get("lag_p95_s"), "s"),
                     fmt_quantity(f.get("lag_max_s"), "s"), fmt_num(f.get("unlit_crossings")),
                     fmt_quantity(f.get("dark_exposure_s"), "s"), fmt_num(f.get("switches")),
                     fmt_quantity(f.get("false_on_time_s"), "lamp-s"), fmt_pct(det.get("tpr")),
                     fmt_pct(det.get("miss_rate"))])  # fmt: skip
    return rows


def _verdict(figures: dict, facts) -> str:
    """The installable controller saving most among those lighting enough entries on entry
    (``wording.best_installable``): never always_on or the oracle, and saving nothing is no win."""
    caveat = f" These figures rest on only {facts.objects} objects: see the warning above." if facts.few_objects else ""
    return f"<p>{html.escape(best_installable_sentence(figures) + caveat)}</p>"


RUN_HEAD = ["controller", "energy", "savings vs always-on", "lag p50", "lag p95", "lag max",
            "never-full crossings", "below-full exposure", "switches", "false on-time", "per-frame TPR",
            "passes missed"]  # fmt: skip


def _run_section(folder: Path, plots: list[Path] | None) -> tuple[str, list[Path]]:
    from citysim.report.run_plots import plot_run
    from citysim.report.runfacts import (
        DETECTION_HEAD,
        detection_figures,
        detection_row,
        detection_sentence,
        load_summary,
        read_passages,
        run_facts,
        zero_savings_reasons,
    )

    paths = plot_run(folder) if plots is None else plots
    summary = load_summary(folder)
    passages = read_passages(folder / "objects.csv")
    facts = run_facts(folder, summary, passages)
    figures = summary["controllers"]
    verdict = _verdict(figures, facts)
    source = summary.get("scenario_file")
    intro = (f"<p>Scenario <b>{html.escape(str(summary.get('scenario')))}</b>"
             + (f" ({html.escape(str(source))})" if source else "")
             + f", seed {summary.get('seed')}, {summary.get('lamps')} lamps.</p>"
             f'<p class="window"><b>What this window is:</b> {html.escape(facts.window_line())}</p>')  # fmt: skip
    # the street's ends with no approach (road users appear inside the end zones) change what
    # lit on entry can be, the oracle's included: said as loudly as the few-objects warning
    for warning in (facts.warning(), describe_short(summary.get("approaches") or {})):
        if warning:
            intro += f'<div class="warning" role="alert">&#9888; {html.escape(warning)}</div>'
    reasons = "".join(f'<p class="reason">{html.escape(r)}</p>'
                      for r in zero_savings_reasons(folder, summary, facts).values())  # fmt: skip
    found = [d for d in (detection_figures(n, f, passages) for n, f in figures.items()) if d]
    detection = ""
    if found:
        detection = ("<h3>Per-frame detection against the crossings</h3>"
                     f'<p class="detection">{html.escape(detection_sentence(found, facts))}</p>'
                     + _table(DETECTION_HEAD, [detection_row(d) for d in found]))  # fmt: skip
    body = (intro + "<h2>Figures per controller</h2>" + _table(RUN_HEAD, _run_rows(figures))
            + f'<p class="howto">{html.escape(RUN_COLUMNS_HOWTO)}</p>' + verdict + reasons + detection)  # fmt: skip
    return body, paths


def best_settings(rows: list[dict[str, str]], axes: list[str]) -> list[dict]:
    """Per controller: the setting (axis values, seeds averaged) with the highest savings among
    those with no never-full crossing (a zone entry whose lamp never reached full level) in any
    seed (or, if none has 0, the fewest in the worst seed), and the one with the lowest mean lag p95."""
    cells: dict[tuple, dict[str, list[float]]] = defaultdict(lambda: defaultdict(list))
    for r in rows:
        if r.get("status") != "ok" or r["controller"] == REFERENCE:
            continue
        key = (r["controller"], *(r.get(a, "") for a in axes))
        for name in ("savings_vs_always_on", "lag_p95_s", "unlit_crossings"):
            cells[key][name].append(to_float(r.get(name)))

    def mean(values: list[float]) -> float:
        finite = [v for v in values if not math.isnan(v)]
        return sum(finite) / len(finite) if finite else math.nan

    out = []
    for controller in dict.fromkeys(k[0] for k in cells):
        mine = {k[1:]: v for k, v in cells.items() if k[0] == controller}
        # the worst seed counts: a setting is as safe as its darkest night
        worst = {k: max((u for u in v["unlit_crossings"] if not math.isnan(u)), default=math.inf)
                 for k, v in mine.items()}  # fmt: skip
        fewest = min(worst.values(), default=math.inf)
        safe = {k: v for k, v in mine.items() if worst[k] == fewest and fewest < math.inf}
        by_savings = max(safe, key=lambda k: mean(safe[k]["savings_vs_always_on"]), default=None)
        with_lag = {k: v for k, v in mine.items() if not math.isnan(mean(v["lag_p95_s"]))}
        by_lag = min(with_lag, key=lambda k: mean(with_lag[k]["lag_p95_s"]), default=None)
        savings_goal = ("highest savings, no never-full crossing" if fewest == 0 else
                        f"highest savings, fewest never-full crossings ({fewest:g}; none has 0)")  # fmt: skip
        for goal, key in ((savings_goal, by_savings), ("lowest lag p95", by_lag)):
            if key is None:
                out.append({"controller": controller, "goal": goal, "setting": None})
                continue
            v = mine[key]
            out.append({"controller": controller, "goal": goal, "setting": dict(zip(axes, key, strict=True)),
                        "savings": mean(v["savings_vs_always_on"]), "lag_p95_s": mean(v["lag_p95_s"]),
                        "unlit_crossings": max(v["unlit_crossings"]), "seeds": len(v["lag_p95_s"])})  # fmt: skip
    return out


def _sweep_section(folder: Path, plots: list[Path] | None) -> tuple[str, list[Path]]:
    from citysim.report.sweep_plots import SweepTable, plot_sweep

    paths = plot_sweep(folder) if plots is None else plots
    table = SweepTable.load(folder)
    axes = table.axes
    sweep = table.sweep
    points = len({r["point_id"] for r in table.ok + table.failed})
    failed_points = {r["point_id"]: r.get("error", "") for r in table.failed}
    axes_text = ", ".join(f"{axis_label(a)} {sweep.get('axes', {}).get(a, [])}" for a in axes)
    intro = (f"<p>Sweep <b>{html.escape(table.name)}</b> over scenario "
             f"<b>{html.escape(str(sweep.get('scenario', '?')))}</b>: axes "
             f"{html.escape(axes_text)}; "
             f"seeds {sweep.get('seeds', '?')}; {fmt_quantity(sweep.get('duration_s'), 's')} simulated per point. "
             f"{points} of {sweep.get('points', '?')} points finished, {len(failed_points)} failed.</p>")  # fmt: skip
    rows = []
    for b in best_settings(table.ok, axes):
        if b["setting"] is None:
            rows.append([b["controller"], b["goal"], "none qualifies", "-", "-", "-", "-"])
            continue
        setting = (
            ", ".join(f"{axis_label(a)} = {v}" for a, v in b["setting"].items()) or "(single point)"
        )
        rows.append([b["controller"], b["goal"], setting, fmt_pct(b["savings"]), fmt_quantity(b["lag_p95_s"], "s"),
                     fmt_num(b["unlit_crossings"]), str(b["seeds"])])  # fmt: skip
    head = ["controller", "goal", "setting", "savings", "lag p95", "never-full crossings (max)", "seeds"]
    body = intro + "<h2>Best settings</h2>" + _table(head, rows, left=3)
    if failed_points:
        shown = list(failed_points.items())[:10]
        body += "<h2>Failed points</h2>" + _table(
            ["point", "error"], [[p, e] for p, e in shown], left=2
        )
        if len(failed_points) > len(shown):
            body += f"<p>... and {len(failed_points) - len(shown)} more (see results.csv).</p>"
    return body, paths


def _sweep_caption_names(folder: Path) -> dict[str, str]:
    """Axis slugs and metric keys of a sweep's plot file names, in words."""
    from citysim.report.sweep_plots import SWEEP_METRICS, SweepTable

    names = {slug(a): axis_label(a) for a in SweepTable.load(folder).axes}
    for key, metric in SWEEP_METRICS.items():
        better = "higher is better" if metric.higher_is_better else "lower is better"
        names[key] = f"{metric.title} ({metric.unit}; {better})"
    return names


def write_report(folder: str | Path, plots: list[Path] | None = None) -> Path:
    """Draw the folder's plots and write FOLDER/report.html (self-contained); returns its path.

    ``plots``: PNGs already drawn for this folder (by ``plot_run`` or ``plot_sweep``), embedded
    as they are instead of drawing them again."""
    folder = Path(folder)
    from citysim.report.year_section import year_section

    year_body = year_section(folder)  # a year section wherever year.json is (`citysim year`)
    if (folder / "results.csv").exists():
        body, paths = _sweep_section(folder, plots)
        kind, names = "sweep", _sweep_caption_names(folder)
    elif (folder / "summary.json").exists():
        body, paths = _run_section(folder, plots)
        kind, names = "run", {}
    elif year_body:
        body, paths, kind, names = "", [], "year", {}
    else:
        raise PlotError(
            f"{folder}: neither a run folder (summary.json) nor a sweep folder (results.csv)"
        )
    title = f"citysim {kind} report: {folder.name}"
    stamp = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    page = "\n".join([
        "<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{html.escape(title)}</title><style>{STYLE}</style></head><body>",
        f"<h1>{html.escape(title)}</h1>", body, year_body, "<h2>Plots</h2>" if kind != "year" else "", _notes(folder),
        *(_figure(p, kind, names) for p in paths),
        f"<p><small>Written {stamp} from {html.escape(str(folder.resolve()))}; "
        f"plots also in {html.escape(str(folder / 'plots'))}/.</small></p>",
        "</body></html>",
    ])  # fmt: skip
    out = folder / "report.html"
    out.write_text(page)
    return out
