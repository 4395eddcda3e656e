"""Planner plots of one run folder: energy per controller, lamp levels with passages, lag CDFs.

``plot_run(run_dir)`` reads DIR/summary.json, DIR/lamps.csv and DIR/objects.csv
(the run folder of ``sim.run_comparison``) and writes DIR/plots/*.png:

* ``energy.png``: energy per controller (kWh), split into luminaire, standby and
  sensing where the summary has the split, labelled with savings vs always-on;
* ``energy_per_hour.png``: energy per hour of the night per controller;
* ``lamp_levels.png``: light level over time of the busiest lamps under every
  controller, with the object passages through each lamp's zone shaded by class;
* ``lag_cdf.png``: share of zone entries lit within a given lag, per class.

Sweep plots live in ``citysim.report.sweep_plots`` (which borrows this module's hourly
bars and lag CDF) and the HTML page in ``citysim.report.html``; neither is imported
here, so the report package has no import circle. Every function returns the paths it wrote.
"""

from __future__ import annotations

import json
import math
from collections import defaultdict
from pathlib import Path

import numpy as np

from citysim.report.common import (
    CLASS_COLORS,
    TARGET_CLASSES,
    PlotError,
    clock_label,
    controller_color,
    ecdf,
    plt,
    read_csv,
    save,
    to_float,
    write_notes,
)

__all__ = ["PlotError", "plot_run"]

#: Lamps shown in lamp_levels.png, and the longest stretch of time shown (s).
LEVEL_PLOT_LAMPS = 3
LEVEL_PLOT_WINDOW_S = 600.0
SPLIT_PARTS = (("luminaire", "luminaire"), ("standby", "driver standby"), ("sensing", "sensing"))


def load_summary(run_dir: Path) -> dict:
    path = run_dir / "summary.json"
    if not path.exists():
        raise PlotError(f"{run_dir}: no summary.json; not a run folder written by `citysim run`")
    try:
        return json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise PlotError(f"{path}: not valid JSON ({exc})") from None


def start_hour_of(summary: dict) -> float | None:
    """The run's clock hour at t = 0, from the summary or its scenario file (None if unknown)."""
    if summary.get("start_hour") is not None:
        return float(summary["start_hour"])
    source = summary.get("scenario_file")
    if source and Path(source).is_file():
        from citysim.config.scenario import ScenarioError, load_scenario

        try:
            return load_scenario(source).start_hour
        except ScenarioError:
            return None
    return None


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
    paths = [plot_energy(summary, plot_dir / "energy.png")]
    paths.append(plot_energy_per_hour(summary, plot_dir / "energy_per_hour.png"))
    levels = plot_lamp_levels(run_dir, summary, passages, plot_dir / "lamp_levels.png", notes)
    paths += [levels] if levels else []
    lag = plot_lag_cdf(passages, controllers, plot_dir / "lag_cdf.png",
                       f"{summary.get('scenario', '')}: ", notes)  # fmt: skip
    paths += [lag] if lag else []
    write_notes(plot_dir, notes)
    return paths


def plot_energy(summary: dict, path: Path) -> Path:
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
        legend = ax.legend(
            title="energy drawn by", loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8
        )
        for handle in legend.legend_handles:
            handle.set_facecolor("white")
    else:
        ax.bar(x, [figures[n]["energy_kwh"] for n in names],
               color=[controller_color(n, names) for n in names], edgecolor="black", linewidth=0.5)  # fmt: skip
    top = max(float(figures[n]["energy_kwh"]) for n in names)
    for i, n in enumerate(names):
        kwh = float(figures[n]["energy_kwh"])
        savings = figures[n].get("savings_vs_always_on")
        text = f"{kwh:.3g} kWh"
        if savings is not None and n != "always_on":
            text += (
                f"\nsaves {100 * savings:.1f} %"
                if savings >= 0
                else f"\nuses {-100 * savings:.1f} % more"
            )
        ax.text(i, kwh + 0.02 * top, text, ha="center", va="bottom", fontsize=8)
    ax.set_xticks(x, names, rotation=20, ha="right")
    ax.set_axisbelow(True)
    ax.set_ylabel("energy over the run (kWh)")
    ax.set_ylim(0, top * 1.25 if top > 0 else 1)
    hours = summary.get("duration_s", 0) / 3600
    ax.set_title(f"{summary.get('scenario', '')}: energy per controller\n"
                 f"{summary.get('lamps', '?')} lamps, {hours:.2g} h simulated, savings vs always-on")  # fmt: skip
    ax.grid(axis="y", alpha=0.3)
    return save(fig, path)


def plot_energy_per_hour(summary: dict, path: Path) -> Path:
    """Grouped bars: energy drawn in each hour of the night, per controller."""
    figures = summary["controllers"]
    names = list(figures)
    per_hour = {
        n: list(figures[n].get("energy_per_hour_kwh") or [figures[n]["energy_kwh"]]) for n in names
    }
    return bars_per_hour(per_hour, start_hour_of(summary), summary.get("duration_s"), path,
                         f"{summary.get('scenario', '')}: energy per hour of the night")  # fmt: skip


def bars_per_hour(per_hour: dict[str, list[float]], start_hour: float | None, duration_s: float | None,
                  path: Path, title: str) -> Path:  # fmt: skip
    names = list(per_hour)
    n_hours = max(len(v) for v in per_hour.values())
    fig, ax = plt.subplots(figsize=(max(5.5, 0.9 * n_hours * max(1, len(names)) / 2 + 3), 4.2))
    width = 0.8 / len(names)
    for i, n in enumerate(names):
        values = per_hour[n] + [math.nan] * (n_hours - len(per_hour[n]))
        ax.bar(np.arange(n_hours) + (i - (len(names) - 1) / 2) * width, values, width,
               label=n, color=controller_color(n, names), edgecolor="black", linewidth=0.4)  # fmt: skip
    if start_hour is not None:
        ticks = [
            f"{clock_label(start_hour, k)}-{clock_label(start_hour, k + 1)}" for k in range(n_hours)
        ]
        ax.set_xlabel("hour of the night (clock time)")
    else:
        ticks = [f"hour {k + 1}" for k in range(n_hours)]
        ax.set_xlabel("hour of the run")
    ax.set_xticks(np.arange(n_hours), ticks, rotation=30 if n_hours > 4 else 0)
    ax.set_axisbelow(True)
    ax.set_ylabel("energy in that hour (kWh)")
    if duration_s is not None and duration_s % 3600 > 1e-6:
        title += f"\n(the last hour is partial: the run lasts {duration_s / 60:.3g} min)"
    ax.set_title(title)
    # beside the bars, not over them (a short run has one hour of tall bars)
    ax.legend(title="controller", fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(axis="y", alpha=0.3)
    return save(fig, path)


def read_passages(path: Path) -> list[dict]:
    """objects.csv rows with numbers parsed (empty list if the file is missing)."""
    if not path.exists():
        return []
    out = []
    for r in read_csv(path):
        out.append({
            "controller": r["controller"], "object_id": r["object_id"], "cls": r["cls"],
            "lamp": int(r["lamp"]), "t_enter_s": to_float(r["t_enter_s"]),
            "t_exit_s": to_float(r["t_exit_s"]), "lag_s": to_float(r["lag_s"]),
        })  # fmt: skip
    return out


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


def plot_lamp_levels(run_dir: Path, summary: dict, passages: list[dict], path: Path,
                     notes: list[str]) -> Path | None:  # fmt: skip
    """Level over time of the busiest lamps per controller, passages shaded by class."""
    lamps_csv = run_dir / "lamps.csv"
    if not lamps_csv.exists():
        notes.append("lamp_levels.png skipped: the run folder has no lamps.csv")
        return None
    names = list(summary["controllers"])
    reference = names[0]  # every controller sees the same traffic: show one controller's passages
    shown = [p for p in passages if p["controller"] == reference and p["cls"] in TARGET_CLASSES]
    counts: dict[int, int] = defaultdict(int)
    for p in shown:
        counts[p["lamp"]] += 1
    n_lamps = int(summary.get("lamps") or 1)
    lamps = sorted(range(n_lamps), key=lambda i: (-counts.get(i, 0), i))[:LEVEL_PLOT_LAMPS]
    lamps.sort()
    t0, t1 = busiest_window(shown, lamps, float(summary.get("duration_s", 0.0)))
    series: dict[tuple[str, int], list[tuple[float, float]]] = defaultdict(list)
    for r in read_csv(lamps_csv):
        lamp = int(r["lamp"])
        if lamp in lamps:
            t = float(r["t_s"])
            if t0 <= t <= t1:
                series[(r["controller"], lamp)].append((t, float(r["level"])))
    if not series:
        notes.append("lamp_levels.png skipped: lamps.csv has no rows")
        return None
    classes = [c for c in TARGET_CLASSES if any(p["cls"] == c for p in shown)]
    row_h = 0.14  # passages are drawn as bars in one row per class below the level axis
    fig, axes = plt.subplots(len(lamps), 1, figsize=(10, (1.6 + 0.25 * len(classes)) * len(lamps) + 1.0),
                             sharex=True, squeeze=False, layout="constrained")  # fmt: skip
    for ax, lamp in zip(axes[:, 0], lamps, strict=True):
        for j, cls in enumerate(classes):
            spans = [(p["t_enter_s"], max(p["t_exit_s"] - p["t_enter_s"], 0.2)) for p in shown
                     if p["lamp"] == lamp and p["cls"] == cls and p["t_exit_s"] >= t0 and p["t_enter_s"] <= t1]  # fmt: skip
            ax.broken_barh(spans, (-(j + 1) * row_h, row_h * 0.75), color=CLASS_COLORS[cls], alpha=0.55,
                           lw=0.3, edgecolor="black", label=f"{cls} in zone")  # fmt: skip
        for k, n in enumerate(names):
            pts = np.array(series.get((n, lamp), []))
            if len(pts):
                ax.plot(pts[:, 0], pts[:, 1] + 0.012 * k, drawstyle="steps-post", lw=1.4,
                        color=controller_color(n, names), label=n)  # fmt: skip
        ax.set_ylim(-(len(classes) + 0.3) * row_h, 1.1)
        rows_y = [-(j + 1) * row_h + row_h * 0.375 for j in range(len(classes))]
        ax.set_yticks([1.0, 0.5, 0.0, *rows_y], ["1", "0.5", "0", *classes], fontsize=8)
        ax.axhline(0, color="black", lw=0.5)
        ax.set_ylabel(f"lamp {lamp}\nlight level (0-1)")
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("simulated time (s)")
    axes[-1, 0].set_xlim(t0, t1)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=min(7, len(labels)), fontsize=8)
    window = (
        "whole run" if t0 == 0 and t1 >= summary.get("duration_s", 0) else f"{t0:.0f}-{t1:.0f} s"
    )
    fig.suptitle(f"{summary.get('scenario', '')}: light level of the {len(lamps)} busiest lamps ({window})\n"
                 "bars below the level: objects passing through the lamp's zone, one bar per passage")  # fmt: skip
    return save(fig, path)


def plot_lag_cdf(passages: list[dict], controllers: list[str], path: Path, title_prefix: str,
                 notes: list[str]) -> Path | None:  # fmt: skip
    """One panel per target class: share of zone entries lit within x seconds, per controller."""
    by_class: dict[str, dict[str, list[float]]] = defaultdict(lambda: defaultdict(list))
    for p in passages:
        if p["cls"] in TARGET_CLASSES and not math.isnan(p["lag_s"]):
            by_class[p["cls"]][p["controller"]].append(p["lag_s"])
    classes = [c for c in TARGET_CLASSES if c in by_class]
    if not classes:
        notes.append(
            "lag_cdf.png skipped: no target object crossed a lamp zone (objects.csv empty or missing)"
        )
        return None
    fig, axes = plt.subplots(1, len(classes), figsize=(3.6 * len(classes) + 0.8, 3.6), squeeze=False,
                             sharey=True)  # fmt: skip
    for ax, cls in zip(axes[0], classes, strict=True):
        lag_max = max(max(v) for v in by_class[cls].values())
        right = max(1.0, lag_max * 1.05)
        for n in controllers:
            lags = by_class[cls].get(n)
            if not lags:
                continue
            x, y = ecdf(np.array(lags))
            lit_pct = 100.0 * np.mean(np.array(lags) <= 0.0)
            ax.step(np.r_[0.0, x, right], np.r_[0.0, y, 1.0], where="post", lw=1.5,
                    color=controller_color(n, controllers), label=f"{n} ({lit_pct:.0f} % lit on entry)")  # fmt: skip
        n_visits = max(len(v) for v in by_class[cls].values())
        ax.set_title(f"{cls} ({n_visits} zone entries)")
        ax.set_xlim(0, right)
        ax.set_xlabel("illumination lag (s)")
        ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("share of zone entries lit within lag")
    axes[0, 0].set_ylim(0, 1.02)
    for ax in axes[0]:
        ax.legend(title="controller", fontsize=7, loc="lower right")
    fig.suptitle(f"{title_prefix}illumination lag per class (0 = lit on entry)", y=1.03)
    return save(fig, path)

