"""Shared pieces of the planner plots: the Agg backend, colours, axis labels, CSV reading, saving.

Plots never touch the simulation: they read a run folder (summary.json,
lamps.csv, objects.csv) or a sweep folder (sweep.json, results.csv) and write
PNGs into DIR/plots/. A plot that cannot be drawn (no data for it) is skipped
and the reason is recorded in DIR/plots/notes.txt, which the report shows.
"""

from __future__ import annotations

import csv
import math
import re
from collections.abc import Iterable, Iterator
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only: no display on a server or in a worker

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from citysim.config.kinds import AGENT_KINDS, TARGET_KINDS  # noqa: E402

__all__ = [
    "CLASS_COLORS",
    "PlotError",
    "axis_label",
    "clock_label",
    "controller_color",
    "ecdf",
    "read_csv",
    "save",
    "to_float",
    "write_notes",
]

DPI = 110
#: Kinds a run's per-class plots show (those present), in registry order, and their colours.
TARGET_CLASSES = TARGET_KINDS
CLASS_COLORS = {name: AGENT_KINDS[name].colour for name in TARGET_KINDS}
#: Fixed colours for the registered controllers, so every plot of a project agrees.
CONTROLLER_COLORS = {
    "always_on": "#7f7f7f",
    "schedule": "#bcbd22",
    "pir": "#ff7f0e",
    "threshold_5": "#8c564b",
    "threshold_05": "#e377c2",
    "detector": "#1f77b4",
    "detector_confirmed": "#2ca02c",
    "detector_network": "#17becf",
}
_SPARE_COLORS = ("#9467bd", "#d62728", "#393b79", "#637939", "#8c6d31", "#843c39")

#: Planner-readable names of the usual sweep axes; others are derived from the dotted path.
AXIS_LABELS = {
    "lamps.camera.height_m": "camera height (m)",
    "lamps.camera.tilt_deg": "camera tilt below horizon (deg)",
    "lamps.pole_height_m": "pole height (m)",
    "lamps.spacing_m": "lamp spacing (m)",
    "lamps.luminaire.hold_s": "hold time after last detection (s)",
    "lamps.luminaire.dim_level": "dim level (fraction of full)",
    "traffic_density": "traffic density (x scenario arrival rates)",
    "environment.wind_mps": "wind (m/s)",
    "environment.insects_per_min": "insects per minute",
}
_UNITS = {"m": "m", "s": "s", "deg": "deg", "mps": "m/s", "kmh": "km/h", "w": "W", "ms": "ms",
          "per_hour": "per hour", "per_min": "per minute"}  # fmt: skip


class PlotError(ValueError):
    """A folder that cannot be plotted; the message names the folder and what is missing."""


def axis_label(path: str) -> str:
    """'lamps.camera.height_m' -> 'camera height (m)'; unknown paths keep their last parts and unit."""
    if path in AXIS_LABELS:
        return AXIS_LABELS[path]
    parts = path.split(".")
    leaf = parts[-1]
    for suffix, unit in sorted(_UNITS.items(), key=lambda kv: -len(kv[0])):
        if leaf.endswith("_" + suffix):
            name = leaf[: -len(suffix) - 1].replace("_", " ")
            owner = parts[-2].replace("_", " ") if len(parts) > 1 else ""
            return f"{owner} {name} ({unit})".strip()
    return " ".join(p.replace("_", " ") for p in parts[-2:])


def controller_color(label: str, order: Iterable[str] = ()) -> str:
    """Fixed colour of a registered controller; other labels get spare colours by position."""
    for name, color in CONTROLLER_COLORS.items():
        if label == name:
            return color
    others = [o for o in order if o not in CONTROLLER_COLORS]
    i = others.index(label) if label in others else len(others)
    return _SPARE_COLORS[i % len(_SPARE_COLORS)]


def clock_label(start_hour: float, hour_index: int) -> str:
    """'22:00' for hour 0 of a run starting at 22.0 (clock hours wrap at midnight)."""
    h = (start_hour + hour_index) % 24.0
    return f"{int(h):02d}:{int(round((h % 1) * 60)) % 60:02d}"


def to_float(text: str | None) -> float:
    """A CSV cell as float; empty or non-numeric cells are NaN."""
    if text is None or text == "":
        return math.nan
    try:
        return float(text)
    except ValueError:
        return math.nan


def read_csv(path: Path) -> Iterator[dict[str, str]]:
    """Stream a CSV file's rows as dicts (memory flat for long runs' lamps.csv)."""
    with open(path, newline="") as f:
        yield from csv.DictReader(f)


def ecdf(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sorted values and the share of values <= each (for a step plot)."""
    x = np.sort(np.asarray(values, dtype=float))
    return x, np.arange(1, len(x) + 1) / max(1, len(x))


def slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9]+", "_", text).strip("_").lower()


def save(fig: plt.Figure, path: Path) -> Path:
    """Write the figure as PNG and free it (long sweeps draw many figures)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI, bbox_inches="tight")
    plt.close(fig)
    return path


def write_notes(plot_dir: Path, notes: list[str]) -> None:
    """DIR/plots/notes.txt: why plots were skipped (removed when nothing was)."""
    path = plot_dir / "notes.txt"
    if notes:
        plot_dir.mkdir(parents=True, exist_ok=True)
        path.write_text("\n".join(notes) + "\n")
    elif path.exists():
        path.unlink()
