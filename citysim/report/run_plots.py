"""Planner plots of one run folder: energy per controller, lamp levels with passages, lag CDFs.

``plot_run(run_dir)`` reads DIR/summary.json, DIR/lamps.csv and DIR/objects.csv
(the run folder of ``citysim.sim.compare.run_comparison``) and writes DIR/plots/*.png:

* ``energy.png``: energy per controller (kWh), split into luminaire, standby and
  sensing where the summary has the split, labelled with savings vs always-on;
* ``oracle_gap.png``: each lamp's energy above the oracle's, per controller
  (``citysim.report.oracle_gap``: where the gap to the bound comes from);
* ``energy_per_hour.png``: energy per clock hour of the night per controller;
* ``lamp_levels.png``: light level over clock time of the busiest lamps, one row of
  panels per controller (true levels, nothing shifted), with the object passages
  through each lamp's zone drawn under each level line by class;
* ``lag_cdf.png``: share of zone entries lit within a given lag, per class, with the
  crossings never lit shown apart as bars (they have no lag to draw); drawn by
  ``citysim.report.lag_cdf``, which sweeps share.

Every legend gives the number of objects behind it, and a run resting on fewer than
``FEW_OBJECTS`` objects gets a warning under each plot. Sweep plots live in
``citysim.report.sweep_plots`` (which borrows this module's hourly bars)
and the HTML page in ``citysim.report.html``; neither is imported here, so the report
package has no import circle. Every function returns the paths it wrote.
"""

from __future__ import annotations

import math
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from citysim.report.common import (
    CLASS_COLORS,
    TARGET_CLASSES,
    PlotError,
    clock_label,
    clock_text,
    controller_color,
    fmt_num,
    fmt_pct,
    plt,
    plural,
    read_csv,
    save,
    set_clock_axis,
    warn_few_objects,
    write_notes,
)
from citysim.report.frontier import frontier_figure
from citysim.report.lag_cdf import plot_lag_cdf
from citysim.report.oracle_gap import plot_oracle_gap
from citysim.report.runfacts import RunFacts, load_summary, read_passages, run_facts

__all__ = ["RUN_PLOTS", "PlotError", "load_summary", "plot_run", "read_passages"]

#: The plots drawn from the run folder's traffic data (each says how many objects it rests on).
TRAFFIC_PLOTS = ("frontier.png", "energy.png", "oracle_gap.png", "energy_per_hour.png", "lamp_levels.png", "lag_cdf.png")
#: Every plot of a run, in the order the report shows them: the traffic plots and the camera coverage map (drawn from the scenario).
RUN_PLOTS = (*TRAFFIC_PLOTS, "coverage.png")
#: Lamps shown in lamp_levels.png, and the longest stretch of time shown (s).
LEVEL_PLOT_LAMPS = 3
LEVEL_PLOT_WINDOW_S = 600.0
SPLIT_PARTS = (("luminaire", "luminaire"), ("standby", "driver standby"), ("sensing", "sensing"))


def objects_note(n_objects: int | None) -> str:
    """'n=12 objects' for a legend title ('' when unknown)."""
    return "" if n_objects is None else f"n={n_objects} {plural(n_objects, 'object')}"


def plot_run(run_dir: str | Path) -> list[Path]:
    """Draw every run plot into RUN_DIR/plots/; returns the PNG paths written."""
    run_dir = Path(run_dir)
    summary = load_summary(run_dir)
    controllers = list(summary.get("controllers", {}))
    if not controllers:
        raise PlotError(f"{run_dir / 'summary.json'}: no controllers in it")
    plot_dir = run_dir / "plots"
    notes: list[str] = []
    passages = read_passages(run_dir / "objects.csv")
    facts = run_facts(run_dir, summary, passages)
    if facts.start_hour is None:
        notes.append(f"time axes in run seconds, not clock time: {facts.scenario_note}")
    frontier = frontier_figure(summary["controllers"], f"{summary.get('scenario', '')}: savings vs darkness",
                               facts.objects)  # fmt: skip
    paths = [save(frontier, plot_dir / "frontier.png")] if frontier else []
    paths.append(plot_energy(summary, facts, plot_dir / "energy.png"))
    gap = plot_oracle_gap(summary, facts.objects, plot_dir / "oracle_gap.png")
    paths += [gap] if gap else []
    paths.append(plot_energy_per_hour(summary, facts, plot_dir / "energy_per_hour.png"))
    levels = plot_lamp_levels(run_dir, summary, passages, facts, plot_dir / "lamp_levels.png", notes)
    paths += [levels] if levels else []
    lag = plot_lag_cdf(passages, controllers, plot_dir / "lag_cdf.png",
                       f"{summary.get('scenario', '')}: ", notes)  # fmt: skip
    paths += [lag] if lag else []
    coverage = plot_dir / "coverage.png"  # drawn by `citysim run` from the scenario's street, kept
    paths += [coverage] if coverage.exists() else []
    write_notes(plot_dir, notes)
    return paths


def plot_energy(summary: dict, facts: RunFacts, path: Path) -> Path:
    """Bars of energy per controller (kWh) labelled with savings vs always-on."""
    figures = summary["controllers"]
    names = list(figures)
    fig, ax = plt.subplots(figsize=(max(5.5, 1.3 * len(names) + 2), 4.2))
    x = np.arange(len(names))
    split = all(isinstance(figures[n].get("energy_split_kwh"), dict) for n in names)
    if split:
        bottom = np.zeros(len(names))
        for (key, label), alpha in zip(SPLIT_PARTS, (1.0, 0.45, 0.7), strict=True):
            part = np.array([float(figures[n]["energy_split_kwh"].get(key, 0.0)) for n in names])
            ax.bar(x, part, bottom=bottom, color=[controller_color(n, names) for n in names],
                   alpha=alpha, edgecolor="black", linewidth=0.5,
                   hatch={"luminaire": None, "standby": "..", "sensing": "//"}[key], label=label)  # fmt: skip
            bottom += part
        title = "energy drawn by" + (f"\n(run: {objects_note(facts.objects)})" if facts.objects is not None else "")
        legend = ax.legend(title=title, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
        for handle in legend.legend_handles:
            handle.set_facecolor("white")
    else:
        ax.bar(x, [figures[n]["energy_kwh"] for n in names],
               color=[controller_color(n, names) for n in names], edgecolor="black", linewidth=0.5)  # fmt: skip
    top = max(float(figures[n]["energy_kwh"]) for n in names)
    for i, n in enumerate(names):
        kwh = float(figures[n]["energy_kwh"])
        savings = figures[n].get("savings_vs_always_on")
        text = f"{fmt_num(kwh)} kWh"
        if savings is not None and n != "always_on":
            text += f"\nsaves {fmt_pct(savings)}" if savings >= 0 else f"\nuses {fmt_pct(-savings)} more"
        ax.text(i, kwh + 0.02 * top, text, ha="center", va="bottom", fontsize=8)
    ax.set_xticks(x, names, rotation=20, ha="right")
    ax.set_axisbelow(True)
    ax.set_ylabel("energy over the run (kWh)")
    ax.set_ylim(0, top * 1.25 if top > 0 else 1)
    span = facts.clock_span() or f"{fmt_num(facts.duration_s / 3600)} h"
    ax.set_title(f"{summary.get('scenario', '')}: energy per controller, {span}\n"
                 f"{summary.get('lamps', '?')} lamps; savings vs always-on")  # fmt: skip
    ax.grid(axis="y", alpha=0.3)
    warn_few_objects(fig, facts.objects)
    return save(fig, path)


def plot_energy_per_hour(summary: dict, facts: RunFacts, path: Path) -> Path:
    """Grouped bars: energy drawn in each hour of the night, per controller."""
    figures = summary["controllers"]
    names = list(figures)
    per_hour = {
        n: list(figures[n].get("energy_per_hour_kwh") or [figures[n]["energy_kwh"]]) for n in names
    }
    return bars_per_hour(per_hour, facts.start_hour, summary.get("duration_s"), path,
                         f"{summary.get('scenario', '')}: energy per hour of the night",
                         legend_note=objects_note(facts.objects), warn_objects=facts.objects)  # fmt: skip


def bars_per_hour(per_hour: dict[str, list[float]], start_hour: float | None, duration_s: float | None,
                  path: Path, title: str, *, legend_note: str = "", warn_objects: int | None = None) -> Path:  # fmt: skip
    """Grouped bars per clock hour; ``legend_note`` (the objects behind them) goes under the legend
    title, and ``warn_objects`` below FEW_OBJECTS writes the few-objects warning."""
    names = list(per_hour)
    n_hours = max(len(v) for v in per_hour.values())
    fig, ax = plt.subplots(figsize=(max(5.5, 0.9 * n_hours * max(1, len(names)) / 2 + 3), 4.2))
    width = 0.8 / len(names)
    for i, n in enumerate(names):
        values = per_hour[n] + [math.nan] * (n_hours - len(per_hour[n]))
        ax.bar(np.arange(n_hours) + (i - (len(names) - 1) / 2) * width, values, width,
               label=n, color=controller_color(n, names), edgecolor="black", linewidth=0.4)  # fmt: skip
    if start_hour is not None:
        ends = [clock_label(start_hour, k + 1) for k in range(n_hours)]
        if duration_s is not None and duration_s < 3600 * n_hours - 1e-6:  # a partial last hour
            ends[-1] = clock_text(start_hour, duration_s)
        ticks = [f"{clock_label(start_hour, k)}-{ends[k]}" for k in range(n_hours)]
        ax.set_xlabel("hour of the night (clock time)")
    else:
        ticks = [f"hour {k + 1}" for k in range(n_hours)]
        ax.set_xlabel("hour of the run")
    ax.set_xticks(np.arange(n_hours), ticks, rotation=30 if n_hours > 4 else 0)
    ax.set_axisbelow(True)
    ax.set_ylabel("energy in that hour (kWh)")
    if duration_s is not None and duration_s % 3600 > 1e-6:
        title += f"\n(the last hour is partial: the run lasts {fmt_num(duration_s / 60)} min)"
    ax.set_title(title)
    legend_title = "controller" + (f"\n({legend_note})" if legend_note else "")
    # beside the bars, not over them (a short run has one hour of tall bars)
    ax.legend(title=legend_title, fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(axis="y", alpha=0.3)
    warn_few_objects(fig, warn_objects)
    return save(fig, path)


def busiest_window(
    passages: list[dict], lamps: list[int], duration_s: float
) -> tuple[float, float]:
    """The LEVEL_PLOT_WINDOW_S stretch with the most passage starts at ``lamps`` (whole run if short)."""
    if duration_s <= LEVEL_PLOT_WINDOW_S:
        return 0.0, duration_s
    starts = np.sort([p["t_enter_s"] for p in passages if p["lamp"] in lamps])
    if len(starts) == 0:
        return 0.0, LEVEL_PLOT_WINDOW_S
    ends = np.searchsorted(starts, starts + LEVEL_PLOT_WINDOW_S * 0.9)
    best = int(np.argmax(ends - np.arange(len(starts))))
    t0 = max(0.0, min(starts[best] - 0.05 * LEVEL_PLOT_WINDOW_S, duration_s - LEVEL_PLOT_WINDOW_S))
    return t0, t0 + LEVEL_PLOT_WINDOW_S


@dataclass
class LevelData:
    """What lamp_levels.png draws: the busiest lamps' levels per controller in one time window."""

    names: list[str]  # controllers, one row of panels each
    lamps: list[int]  # the busiest lamps, one column each
    t0_s: float
    t1_s: float
    series: dict[tuple[str, int], np.ndarray]  # (controller, lamp) -> (N, 2) of (t_s, level)
    passages: list[dict]  # target passages at those lamps (the first controller's: same traffic)
    classes: list[str] = field(default_factory=list)
    dim_level: float | None = None


def level_data(run_dir: Path, summary: dict, passages: list[dict], facts: RunFacts) -> LevelData | str:
    """The data of lamp_levels.png, or why it cannot be drawn."""
    lamps_csv = run_dir / "lamps.csv"
    if not lamps_csv.exists():
        return "lamp_levels.png skipped: the run folder has no lamps.csv"
    names = list(summary["controllers"])
    reference = names[0]  # every controller sees the same traffic: show one controller's passages
    shown = [p for p in passages if p["controller"] == reference and p["cls"] in TARGET_CLASSES]
    counts: dict[int, int] = defaultdict(int)
    for p in shown:
        counts[p["lamp"]] += 1
    n_lamps = int(summary.get("lamps") or 1)
    lamps = sorted(sorted(range(n_lamps), key=lambda i: (-counts.get(i, 0), i))[:LEVEL_PLOT_LAMPS])
    t0, t1 = busiest_window(shown, lamps, float(summary.get("duration_s", 0.0)))
    series: dict[tuple[str, int], list[tuple[float, float]]] = defaultdict(list)
    for r in read_csv(lamps_csv):
        lamp = int(r["lamp"])
        if lamp in lamps:
            t = float(r["t_s"])
            if t0 <= t <= t1:
                series[(r["controller"], lamp)].append((t, float(r["level"])))
    if not series:
        return "lamp_levels.png skipped: lamps.csv has no rows"
    in_window = [p for p in shown if p["lamp"] in lamps and p["t_exit_s"] >= t0 and p["t_enter_s"] <= t1]
    classes = [c for c in TARGET_CLASSES if any(p["cls"] == c for p in in_window)]
    dim = facts.scenario.lamps.luminaire.dim_level if facts.scenario is not None else None
    return LevelData(names, lamps, t0, t1, {k: np.array(v) for k, v in series.items()}, in_window,
                     classes, dim)  # fmt: skip


def plot_lamp_levels(run_dir: Path, summary: dict, passages: list[dict], facts: RunFacts, path: Path,
                     notes: list[str]) -> Path | None:  # fmt: skip
    """Level over time of the busiest lamps, one row per controller, passages drawn by class."""
    data = level_data(run_dir, summary, passages, facts)
    if isinstance(data, str):
        notes.append(data)
        return None
    window = ("whole run" if data.t0_s == 0 and data.t1_s >= summary.get("duration_s", 0)
              else f"busiest {fmt_num(LEVEL_PLOT_WINDOW_S / 60)} min")  # fmt: skip
    title = (f"{summary.get('scenario', '')}: light level of the {len(data.lamps)} busiest lamps "
             f"({window}), one row per controller\n"
             "true levels (1 = full); bars under each line: objects in that lamp's zone")  # fmt: skip
    return save(draw_lamp_levels(data, facts, title), path)


ROW_H = 0.14  # height of one class's row of passage bars under a level panel (level units)


def draw_lamp_levels(data: LevelData, facts: RunFacts, title: str) -> Figure:
    """Small multiples: rows are controllers, columns lamps; each panel one lamp's true level.

    Every panel gets the same limits and ticks explicitly rather than through shared axes: with a
    row per controller, matplotlib's shared-axis bookkeeping grows with the square of the panels
    (eleven controllers took seconds per figure) and draws the same picture."""
    rows, cols = len(data.names), len(data.lamps)
    fig, axes = plt.subplots(rows, cols, squeeze=False, layout="constrained",
                             figsize=(3.4 * cols + 1.8, (0.95 + 0.18 * len(data.classes)) * rows + 1.8))  # fmt: skip
    ticks = sorted({0.0, 0.5, 1.0} | ({data.dim_level} if data.dim_level else set()))
    rows_y = [-(j + 1) * ROW_H + ROW_H * 0.375 for j in range(len(data.classes))]
    y_low = -(len(data.classes) + 0.3) * ROW_H
    for i, name in enumerate(data.names):
        for j, lamp in enumerate(data.lamps):
            ax = axes[i, j]
            ax.set_autoscale_on(False)
            ax.set_ylim(y_low, 1.12)
            _draw_passages(ax, data, lamp)
            pts = data.series.get((name, lamp))
            if pts is not None and len(pts):
                ax.plot(pts[:, 0], pts[:, 1], drawstyle="steps-post", lw=1.4,
                        color=controller_color(name, data.names))  # fmt: skip
            ax.axhline(0, color="black", lw=0.5)
            ax.grid(alpha=0.3)
            if i == 0:
                n_pass = sum(p["lamp"] == lamp for p in data.passages)
                ax.set_title(f"lamp {lamp} ({n_pass} {plural(n_pass, 'passage')})", fontsize=9)
            set_clock_axis(ax, facts.start_hour, data.t0_s, data.t1_s)
            ax.set_yticks([*ticks, *rows_y], [fmt_num(t) for t in ticks] + data.classes, fontsize=7)
            ax.tick_params(axis="x", labelsize=7, rotation=30, labelbottom=i == rows - 1)
            ax.tick_params(axis="y", labelsize=7, labelleft=j == 0)
            if i < rows - 1:
                ax.set_xlabel("")
        axes[i, 0].set_ylabel(f"{name}\nlevel", fontsize=8, color=controller_color(name, data.names))
    handles, labels = [], []
    for cls in data.classes:
        n_obj = len({p["object_id"] for p in data.passages if p["cls"] == cls})
        handles.append(plt.Rectangle((0, 0), 1, 1, color=CLASS_COLORS[cls], alpha=0.55))
        labels.append(f"{cls} in zone (n={n_obj})")
    if handles:
        fig.legend(handles, labels, loc="outside lower center", ncol=len(handles), fontsize=8,
                   title="objects passing these lamps", title_fontsize=8)  # fmt: skip
    fig.suptitle(title, fontsize=10)
    warn_few_objects(fig, facts.objects)
    return fig


def _draw_passages(ax, data: LevelData, lamp: int) -> None:
    """One bar per passage through ``lamp``'s zone, one row per class, under the level axis."""
    for j, cls in enumerate(data.classes):
        spans = [(p["t_enter_s"], max(p["t_exit_s"] - p["t_enter_s"], 0.2)) for p in data.passages
                 if p["lamp"] == lamp and p["cls"] == cls]  # fmt: skip
        ax.broken_barh(spans, (-(j + 1) * ROW_H, ROW_H * 0.75), color=CLASS_COLORS[cls], alpha=0.55,
                       lw=0.3, edgecolor="black")  # fmt: skip
