"""Planner plots of a sweep folder: savings and lag along each axis, heatmaps over two axes.

``plot_sweep(sweep_dir)`` reads DIR/sweep.json and DIR/results.csv (written by
``citysim.sweep.runner.run_sweep``) and writes DIR/plots/*.png:

* ``vs_<axis>.png`` for every axis with two or more values: energy savings and
  lag p95 against the axis (e.g. traffic density), one line per controller,
  the mean over seeds and the other axes with their min-max band;
* ``heatmap_<metric>.png`` over two axes (camera height x tilt when the sweep
  has both, else its first two axes) for every metric of ``SWEEP_METRICS``:
  savings, false negative rate, false positive rate and lag p95, one panel
  per controller with a shared colour scale;
* ``energy_per_hour.png``: mean energy per hour of the night per controller;
* ``lag_cdf.png``: lag CDF per class over all points (needs the points' objects.csv).

Only rows with status ``ok`` are plotted; heatmap cells whose points all
failed are marked. always_on is the reference (0 % savings, no lag) and is
left out of the savings and lag panels.
"""

from __future__ import annotations

import json
import math
from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from citysim.report.common import (
    PlotError,
    axis_label,
    controller_color,
    fmt_num,
    plt,
    read_csv,
    save,
    slug,
    to_float,
    write_notes,
)
from citysim.report.frontier import sweep_frontier_figure
from citysim.report.lag_cdf import plot_lag_cdf
from citysim.report.run_plots import bars_per_hour
from citysim.report.runfacts import read_passages

__all__ = ["SWEEP_METRICS", "SweepTable", "plot_sweep"]

REFERENCE = "always_on"


def column(name: str) -> Callable[[dict[str, str]], float]:
    return lambda row: to_float(row.get(name))


def false_negative_rate(row: dict[str, str]) -> float:
    """Share of object passes never detected; 1 - tpr where the miss rate is not reported."""
    miss = to_float(row.get("detection.miss_rate"))
    if not math.isnan(miss):
        return miss
    return 1.0 - to_float(row.get("detection.tpr"))


@dataclass(frozen=True)
class Metric:
    """A figure of the results table as plotted: title, unit, scale to that unit, colour map."""

    title: str
    unit: str
    scale: float
    cmap: str
    value: Callable[[dict[str, str]], float]
    higher_is_better: bool


#: Metrics drawn as heatmaps (and, for savings and lag, along each axis), by file name.
SWEEP_METRICS: dict[str, Metric] = {
    "savings": Metric("energy savings vs always-on", "%", 100.0, "viridis",
                      column("savings_vs_always_on"), True),
    "false_negative_rate": Metric("false negative rate (object passes never detected)", "%", 100.0,
                                  "magma_r", false_negative_rate, False),
    "false_positive_rate": Metric("false positive rate (noise regions taken for targets)", "%", 100.0,
                                  "magma_r", column("detection.fpr"), False),
    "lag_p95": Metric("illumination lag p95", "s", 1.0, "magma_r", column("lag_p95_s"), False),
}  # fmt: skip


def _axis_value(text: str) -> float | str:
    value = to_float(text)
    return text if math.isnan(value) else value


@dataclass
class SweepTable:
    """sweep.json and results.csv of a sweep folder, with the rows split by status."""

    folder: Path
    sweep: dict
    ok: list[dict[str, str]]
    failed: list[dict[str, str]]

    @classmethod
    def load(cls, folder: str | Path) -> SweepTable:
        folder = Path(folder)
        results = folder / "results.csv"
        if not results.exists():
            raise PlotError(
                f"{folder}: no results.csv; not a sweep folder written by `citysim sweep`"
            )
        sweep_json = folder / "sweep.json"
        sweep = json.loads(sweep_json.read_text()) if sweep_json.exists() else {}
        rows = list(read_csv(results))
        if not sweep:
            fixed = {"point_id", "seed", "controller", "status", "error", "finished_at", "wall_s"}
            header = list(rows[0]) if rows else []
            end = header.index("seed") if "seed" in header else 1
            sweep = {"name": folder.name, "axes": {a: [] for a in header[1:end] if a not in fixed}}
        ok = [r for r in rows if r.get("status") == "ok"]
        failed = [r for r in rows if r.get("status") == "failed"]
        return cls(folder, sweep, ok, failed)

    @property
    def name(self) -> str:
        return self.sweep.get("name", self.folder.name)

    @property
    def axes(self) -> list[str]:
        return list(self.sweep.get("axes", {}))

    @property
    def controllers(self) -> list[str]:
        listed = list(self.sweep.get("controllers", []))
        seen = listed + sorted({r["controller"] for r in self.ok} - set(listed))
        return [c for c in seen if any(r["controller"] == c for r in self.ok)]

    def values(self, axis: str) -> list[float | str]:
        found = {_axis_value(r[axis]) for r in self.ok + self.failed if axis in r}
        numeric = sorted(v for v in found if isinstance(v, float))
        return numeric + sorted(v for v in found if isinstance(v, str))

    def n_seeds(self) -> int:
        return len({r["seed"] for r in self.ok}) or 1

    def mean_objects(self) -> float | None:
        """Mean number of objects crossing a lamp zone per finished point (None if not recorded)."""
        per_point = {r["point_id"]: to_float(r.get("objects")) for r in self.ok}
        finite = [v for v in per_point.values() if not math.isnan(v)]
        return sum(finite) / len(finite) if finite else None

    def objects_note(self) -> str:
        """'mean n=41 objects per point' for legends ('' when results.csv has no objects column)."""
        n = self.mean_objects()
        return "" if n is None else f"mean n={fmt_num(n)} objects per point"

    def legend_title(self) -> str:
        note = self.objects_note()
        return "controller" + (f"\n({note})" if note else "")


def plot_sweep(sweep_dir: str | Path) -> list[Path]:
    """Draw every sweep plot into SWEEP_DIR/plots/; returns the PNG paths written."""
    table = SweepTable.load(sweep_dir)
    plot_dir = table.folder / "plots"
    notes: list[str] = []
    if not table.ok:
        write_notes(
            plot_dir,
            [f"no plots: results.csv has no finished (ok) rows ({len(table.failed)} failed)"],
        )
        return []
    paths: list[Path] = []
    varied = [a for a in table.axes if len(table.values(a)) >= 2]
    for axis in varied:
        paths.append(plot_along_axis(table, axis, plot_dir / f"vs_{slug(axis)}.png"))
    if len(table.axes) == 1 and not varied:
        notes.append("no axis plots: the sweep's only axis has a single value")
    pair = heatmap_axes(table, varied)
    if pair is None:
        notes.append("no heatmaps: they need two axes with two or more values each")
    else:
        for key, metric in SWEEP_METRICS.items():
            path = plot_heatmap(table, pair, metric, plot_dir / f"heatmap_{key}.png")
            if path is None:
                notes.append(f"heatmap_{key}.png skipped: no controller reports {metric.title}")
            else:
                paths.append(path)
    frontier = sweep_frontier_figure(table.ok, varied[0] if len(varied) == 1 else None)
    paths += [save(frontier, plot_dir / "frontier.png")] if frontier else []
    energy = plot_sweep_energy_per_hour(table, plot_dir / "energy_per_hour.png")
    paths += [energy] if energy else []
    lag = plot_sweep_lag_cdf(table, plot_dir / "lag_cdf.png", notes)
    paths += [lag] if lag else []
    write_notes(plot_dir, notes)
    return paths


def _group(
    rows: list[dict[str, str]], keys: list[str], metric: Callable[[dict[str, str]], float]
) -> dict:
    """(controller, *key values) -> finite metric values."""
    out: dict[tuple, list[float]] = defaultdict(list)
    for r in rows:
        v = metric(r)
        if not math.isnan(v):
            out[(r["controller"], *(_axis_value(r[k]) for k in keys))].append(v)
    return out


def plot_along_axis(table: SweepTable, axis: str, path: Path) -> Path:
    """Savings and lag p95 against one axis, per controller: mean and min-max band."""
    values = table.values(axis)
    numeric = all(isinstance(v, float) for v in values)
    xs = np.array(values, dtype=float) if numeric else np.arange(len(values), dtype=float)
    controllers = [c for c in table.controllers if c != REFERENCE]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    for ax, key in zip(axes, ("savings", "lag_p95"), strict=True):
        metric = SWEEP_METRICS[key]
        groups = _group(table.ok, [axis], metric.value)
        for c in controllers:
            stats = [groups.get((c, v), []) for v in values]
            mean = np.array([np.mean(s) if s else np.nan for s in stats]) * metric.scale
            if np.all(np.isnan(mean)):
                continue
            lo = np.array([np.min(s) if s else np.nan for s in stats]) * metric.scale
            hi = np.array([np.max(s) if s else np.nan for s in stats]) * metric.scale
            color = controller_color(c, table.controllers)
            ax.plot(xs, mean, "o-", color=color, label=c, lw=1.6, ms=4)
            ax.fill_between(xs, lo, hi, color=color, alpha=0.15, lw=0)
        ax.set_xlabel(axis_label(axis))
        ax.set_ylabel(f"{metric.title} ({metric.unit})")
        ax.set_title(metric.title)
        if not numeric:
            ax.set_xticks(xs, [str(v) for v in values])
        ax.grid(alpha=0.3)
        ax.legend(title=table.legend_title(), fontsize=8, title_fontsize=8)
    others = [a for a in table.axes if a != axis]
    spread = f"mean over {table.n_seeds()} seed(s)" + (
        f" and {', '.join(map(axis_label, others))}" if others else ""
    )
    fig.suptitle(f"{table.name}: savings and lag vs {axis_label(axis)}\n{spread}; band: min-max")
    return save(fig, path)


def heatmap_axes(table: SweepTable, varied: list[str]) -> tuple[str, str] | None:
    """(row axis, column axis): camera height x tilt when swept, else the first two varied axes."""
    if "lamps.camera.height_m" in varied and "lamps.camera.tilt_deg" in varied:
        return "lamps.camera.height_m", "lamps.camera.tilt_deg"
    return (varied[0], varied[1]) if len(varied) >= 2 else None


def plot_heatmap(
    table: SweepTable, pair: tuple[str, str], metric: Metric, path: Path
) -> Path | None:
    """One panel per controller with data; cells are means over seeds and the other axes."""
    row_axis, col_axis = pair
    rows_v, cols_v = table.values(row_axis), table.values(col_axis)
    groups = _group(table.ok, [row_axis, col_axis], metric.value)
    failed_cells = {(_axis_value(r[row_axis]), _axis_value(r[col_axis])) for r in table.failed}
    ok_cells = {(_axis_value(r[row_axis]), _axis_value(r[col_axis])) for r in table.ok}
    grids = {}
    for c in table.controllers:
        if c == REFERENCE:
            continue
        grid = np.full((len(rows_v), len(cols_v)), np.nan)
        for i, rv in enumerate(rows_v):
            for j, cv in enumerate(cols_v):
                vals = groups.get((c, rv, cv))
                if vals:
                    grid[i, j] = np.mean(vals) * metric.scale
        if not np.all(np.isnan(grid)):
            grids[c] = grid
    if not grids:
        return None
    stacked = np.stack(list(grids.values()))
    vmin, vmax = float(np.nanmin(stacked)), float(np.nanmax(stacked))
    if vmin == vmax:
        vmin, vmax = vmin - 1.0, vmax + 1.0
    n = len(grids)
    fig, axes = plt.subplots(1, n, figsize=(0.55 * len(cols_v) * n + 2.2 * n + 1.2, 0.5 * len(rows_v) + 2.6),
                             squeeze=False, layout="constrained")  # fmt: skip
    cmap = plt.get_cmap(metric.cmap).with_extremes(bad="#dddddd")
    image = None
    for ax, (c, grid) in zip(axes[0], grids.items(), strict=True):
        image = ax.imshow(grid, origin="lower", aspect="auto", cmap=cmap, vmin=vmin, vmax=vmax)
        for i, rv in enumerate(rows_v):
            for j, cv in enumerate(cols_v):
                if not np.isnan(grid[i, j]):
                    shade = (grid[i, j] - vmin) / (vmax - vmin)
                    dark = shade < 0.5 if metric.cmap == "viridis" else shade > 0.5
                    ax.text(j, i, fmt_num(grid[i, j]), ha="center", va="center", fontsize=7,
                            color="white" if dark else "black")  # fmt: skip
                elif (rv, cv) in failed_cells and (rv, cv) not in ok_cells:
                    ax.text(j, i, "failed", ha="center", va="center", fontsize=7, color="#aa0000")
        ax.set_xticks(range(len(cols_v)), [f"{v:g}" if isinstance(v, float) else v for v in cols_v])
        ax.set_yticks(range(len(rows_v)), [f"{v:g}" if isinstance(v, float) else v for v in rows_v])
        ax.set_xlabel(axis_label(col_axis))
        ax.set_ylabel(axis_label(row_axis))
        ax.set_title(c)
    fig.colorbar(image, ax=axes[0].tolist(), label=f"{metric.title} ({metric.unit})", shrink=0.9)
    better = "higher is better" if metric.higher_is_better else "lower is better"
    fig.suptitle(f"{table.name}: {metric.title} ({metric.unit}; {better})\n"
                 f"mean over {table.n_seeds()} seed(s); grey: no data")  # fmt: skip
    return save(fig, path)


def plot_sweep_energy_per_hour(table: SweepTable, path: Path) -> Path | None:
    """Mean energy per hour of the night over all finished points, per controller."""
    sums: dict[str, list[list[float]]] = defaultdict(list)
    for r in table.ok:
        text = r.get("energy_per_hour_kwh", "")
        if text:
            sums[r["controller"]].append(json.loads(text))
    if not sums:
        return None
    per_hour = {}
    for c in table.controllers:
        if c in sums:
            n_hours = max(len(v) for v in sums[c])
            padded = np.array([v + [np.nan] * (n_hours - len(v)) for v in sums[c]], dtype=float)
            per_hour[c] = list(np.nanmean(padded, axis=0))
    return bars_per_hour(per_hour, table.sweep.get("start_hour"), table.sweep.get("duration_s"), path,
                         f"{table.name}: energy per hour of the night (mean over {len(table.ok) // max(1, len(per_hour))} points)",
                         legend_note=table.objects_note())  # fmt: skip


def plot_sweep_lag_cdf(table: SweepTable, path: Path, notes: list[str]) -> Path | None:
    """Lag CDF per class pooled over every finished point's objects.csv."""
    ok_points = sorted({r["point_id"] for r in table.ok})
    passages = []
    found = 0
    for pid in ok_points:
        objects = table.folder / "points" / pid / "objects.csv"
        if objects.exists():
            found += 1
            for p in read_passages(objects):
                p["source"] = pid  # object ids restart at every point: count objects per point
                passages.append(p)
    if not found:
        notes.append(
            "lag_cdf.png skipped: the points' objects.csv were not kept (save_objects: false)"
        )
        return None
    return plot_lag_cdf(
        passages, table.controllers, path, f"{table.name}: pooled over {found} points, ", notes
    )
