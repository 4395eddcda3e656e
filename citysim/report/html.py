"""One self-contained HTML page per run or sweep folder: every plot, the figures, the best settings.

``write_report(folder)`` redraws the folder's plots (``plots.plot_run`` for a run
folder with summary.json, ``plots_sweep.plot_sweep`` for a sweep folder with
results.csv) and writes FOLDER/report.html with each PNG embedded as a base64
data URI, so the page opens anywhere (mail it, put it on a share) without the
plots folder. It shows a table of figures per controller (run) or the best
settings per controller (sweep): the highest savings among settings where no
object crossed an unlit zone (``unlit_crossings == 0``), and the lowest lag p95.
"""

from __future__ import annotations

import base64
import html
import math
from collections import defaultdict
from datetime import UTC, datetime
from pathlib import Path

from citysim.report.common import PlotError, axis_label, to_float

__all__ = ["best_settings", "write_report"]

REFERENCE = "always_on"
STYLE = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1150px; color: #222; }
h1 { font-size: 1.5em; } h2 { font-size: 1.2em; margin-top: 1.8em; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; font-size: 0.9em; margin: 0.6em 0; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.6em; text-align: right; }
th { background: #f2f2f2; } td.l, th.l { text-align: left; }
figure { margin: 1.2em 0; } img { max-width: 100%; border: 1px solid #eee; }
figcaption { font-size: 0.85em; color: #555; } .note { color: #8a5a00; }
"""


def _fmt(value: float | None, digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    return f"{value:.{digits}g}"


def _pct(fraction: float | None) -> str:
    if fraction is None or (isinstance(fraction, float) and math.isnan(fraction)):
        return "-"
    return f"{100 * fraction:.1f} %"


def _table(head: list[str], rows: list[list[str]], left: int = 1) -> str:
    def cell(tag: str, i: int, text: str) -> str:
        cls = ' class="l"' if i < left else ""
        return f"<{tag}{cls}>{html.escape(text)}</{tag}>"

    out = ["<table><tr>" + "".join(cell("th", i, h) for i, h in enumerate(head)) + "</tr>"]
    for r in rows:
        out.append("<tr>" + "".join(cell("td", i, c) for i, c in enumerate(r)) + "</tr>")
    return "\n".join(out) + "</table>"


def _figure(path: Path) -> str:
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    name = html.escape(path.name)
    return (f'<figure><img alt="{name}" src="data:image/png;base64,{data}">'
            f"<figcaption>{name}</figcaption></figure>")  # fmt: skip


def _notes(folder: Path) -> str:
    path = folder / "plots" / "notes.txt"
    if not path.exists():
        return ""
    lines = [line for line in path.read_text().splitlines() if line.strip()]
    return "".join(f'<p class="note">{html.escape(line)}</p>' for line in lines)


def _run_section(folder: Path, plots: list[Path] | None) -> tuple[str, list[Path]]:
    from citysim.report.run_plots import load_summary, plot_run

    paths = plot_run(folder) if plots is None else plots
    summary = load_summary(folder)
    figures = summary["controllers"]
    rows = []
    for name, f in figures.items():
        det = f.get("detection") or {}
        rows.append([name, _fmt(f.get("energy_kwh")), _pct(f.get("savings_vs_always_on")),
                     _fmt(f.get("lag_p50_s")), _fmt(f.get("lag_p95_s")), _fmt(f.get("lag_max_s")),
                     str(f.get("unlit_crossings", "-")), _fmt(f.get("dark_exposure_s")),
                     str(f.get("switches", "-")), _fmt(f.get("false_on_time_s")),
                     _pct(det.get("tpr")), _pct(det.get("miss_rate"))])  # fmt: skip
    head = ["controller", "energy kWh", "savings", "lag p50 s", "lag p95 s", "lag max s", "unlit crossings",
            "dark exposure s", "switches", "false-on s", "TPR", "miss rate"]  # fmt: skip
    safe = [(n, f) for n, f in figures.items() if n != REFERENCE and f.get("unlit_crossings") == 0]
    best = max(safe, key=lambda nf: nf[1].get("savings_vs_always_on") or -math.inf, default=None)
    verdict = (f"<p>Best controller with no unlit crossing: <b>{html.escape(best[0])}</b>, saving "
               f"{_pct(best[1].get('savings_vs_always_on'))} against always-on.</p>" if best else
               "<p>Every smart controller let some object cross an unlit zone.</p>")  # fmt: skip
    intro = (f"<p>Scenario <b>{html.escape(str(summary.get('scenario')))}</b>, seed {summary.get('seed')}, "
             f"{_fmt(summary.get('duration_s', 0) / 3600, 3)} h simulated, {summary.get('lamps')} lamps.</p>")  # fmt: skip
    return intro + "<h2>Figures per controller</h2>" + _table(head, rows) + verdict, paths


def best_settings(rows: list[dict[str, str]], axes: list[str]) -> list[dict]:
    """Per controller: the setting (axis values, seeds averaged) with the highest savings among
    those with no unlit crossing in any seed (or, if none has 0, the fewest in the worst seed),
    and the one with the lowest mean lag p95."""
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
        savings_goal = ("highest savings, no unlit crossing" if fewest == 0 else
                        f"highest savings, fewest unlit crossings ({fewest:g}; none has 0)")  # fmt: skip
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
             f"seeds {sweep.get('seeds', '?')}; {_fmt(sweep.get('duration_s'))} s simulated per point. "
             f"{points} of {sweep.get('points', '?')} points finished, {len(failed_points)} failed.</p>")  # fmt: skip
    rows = []
    for b in best_settings(table.ok, axes):
        if b["setting"] is None:
            rows.append([b["controller"], b["goal"], "none qualifies", "-", "-", "-", "-"])
            continue
        setting = (
            ", ".join(f"{axis_label(a)} = {v}" for a, v in b["setting"].items()) or "(single point)"
        )
        rows.append([b["controller"], b["goal"], setting, _pct(b["savings"]), _fmt(b["lag_p95_s"]),
                     _fmt(b["unlit_crossings"]), str(b["seeds"])])  # fmt: skip
    head = [
        "controller",
        "goal",
        "setting",
        "savings",
        "lag p95 s",
        "unlit crossings (max)",
        "seeds",
    ]
    body = intro + "<h2>Best settings</h2>" + _table(head, rows, left=3)
    if failed_points:
        shown = list(failed_points.items())[:10]
        body += "<h2>Failed points</h2>" + _table(
            ["point", "error"], [[p, e] for p, e in shown], left=2
        )
        if len(failed_points) > len(shown):
            body += f"<p>... and {len(failed_points) - len(shown)} more (see results.csv).</p>"
    return body, paths


def write_report(folder: str | Path, plots: list[Path] | None = None) -> Path:
    """Draw the folder's plots and write FOLDER/report.html (self-contained); returns its path.

    ``plots``: PNGs already drawn for this folder (by ``plot_run`` or ``plot_sweep``), embedded
    as they are instead of drawing them again."""
    folder = Path(folder)
    if (folder / "results.csv").exists():
        body, paths = _sweep_section(folder, plots)
        kind = "sweep"
    elif (folder / "summary.json").exists():
        body, paths = _run_section(folder, plots)
        kind = "run"
    else:
        raise PlotError(
            f"{folder}: neither a run folder (summary.json) nor a sweep folder (results.csv)"
        )
    title = f"citysim {kind} report: {folder.name}"
    stamp = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    page = "\n".join([
        "<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{html.escape(title)}</title><style>{STYLE}</style></head><body>",
        f"<h1>{html.escape(title)}</h1>", body, "<h2>Plots</h2>", _notes(folder),
        *(_figure(p) for p in paths),
        f"<p><small>Written {stamp} from {html.escape(str(folder.resolve()))}; "
        f"plots also in {html.escape(str(folder / 'plots'))}/.</small></p>",
        "</body></html>",
    ])  # fmt: skip
    out = folder / "report.html"
    out.write_text(page)
    return out
