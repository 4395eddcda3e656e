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
    "FEW_OBJECTS",
    "PlotError",
    "axis_label",
    "clock_label",
    "clock_text",
    "controller_color",
    "ecdf",
    "fmt_num",
    "fmt_pct",
    "fmt_quantity",
    "plural",
    "read_csv",
    "save",
    "set_clock_axis",
    "to_float",
    "warn_few_objects",
    "write_notes",
]

DPI = 110
#: Below this many objects crossing a lamp zone, a run's percentages hang on a handful of
#: crossings (one more unlit crossing moves them by several points): plots and report say so.
FEW_OBJECTS = 30
WARNING_COLOR = "#b00000"
#: Kinds a run's per-class plots show (those present), in registry order, and their colours.
TARGET_CLASSES = TARGET_KINDS
CLASS_COLORS = {name: AGENT_KINDS[name].colour for name in TARGET_KINDS}
#: Fixed colours for the registered controllers, so every plot of a project agrees.
CONTROLLER_COLORS = {
    "always_on": "#7f7f7f",
    "oracle": "#000000",
    "schedule": "#bcbd22",
    "pir": "#ff7f0e",
    "threshold_5": "#8c564b",
    "threshold_05": "#e377c2",
    "detector": "#1f77b4",
    "detector_confirmed": "#2ca02c",
    "detector_network": "#17becf",
    "detector_located": "#d62728",
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


def clock_text(start_hour: float, t_s: float, seconds: bool = False) -> str:
    """Clock time of run second ``t_s`` for a run starting at ``start_hour``: '22:05' (or '22:05:30')."""
    total_s = int(round(start_hour * 3600.0 + t_s)) % 86400
    h, rest = divmod(total_s, 3600)
    m, sec = divmod(rest, 60)
    return f"{h:02d}:{m:02d}:{sec:02d}" if seconds else f"{h:02d}:{m:02d}"


#: Tick spacings tried for a clock axis (s): the first giving at most CLOCK_TICKS_MAX ticks wins.
_CLOCK_STEPS_S = (1, 2, 5, 10, 15, 30, 60, 120, 300, 600, 900, 1800, 3600, 7200)
CLOCK_TICKS_MAX = 8


def set_clock_axis(ax, start_hour: float | None, t0_s: float, t1_s: float) -> None:
    """Ticks of a run-time x axis as clock time (HH:MM, HH:MM:SS below minute spacing).

    Without a start hour (the scenario file is not found) the axis stays in run seconds.
    """
    ax.set_xlim(t0_s, t1_s)
    if start_hour is None:
        ax.set_xlabel("time since the run started (s)")
        return
    span_s = max(t1_s - t0_s, 1e-9)
    step = next((s for s in _CLOCK_STEPS_S if span_s / s <= CLOCK_TICKS_MAX), _CLOCK_STEPS_S[-1])
    # ticks on whole clock steps (22:05, not 22:04:37), counted from the run's start
    offset_s = (start_hour * 3600.0) % step
    first = math.ceil((t0_s + offset_s) / step) * step - offset_s
    ticks = np.arange(first, t1_s + 1e-9, step)
    ax.set_xticks(ticks, [clock_text(start_hour, t, seconds=step < 60) for t in ticks])
    ax.set_xlabel("clock time")


def plural(n: int, word: str) -> str:
    """'1 object', '2 objects': the word for a count."""
    return word if n == 1 else word + "s"


def fmt_num(value: float | None, digits: int = 3) -> str:
    """A number for people: 5818.3 -> '5,818', 0.05466 -> '0.0547', 1.0 -> '1'; never '5.82e+03'.

    Keeps ``digits`` significant digits below 10**digits and every integer digit above
    (with thousands separators); None and NaN print as '-'.
    """
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if isinstance(value, bool):
        return str(value)
    v = float(value)
    if math.isinf(v):
        return "infinite" if v > 0 else "-infinite"
    if v == 0:
        return "0"
    decimals = max(0, digits - 1 - math.floor(math.log10(abs(v))))
    text = f"{v:,.{decimals}f}"
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def fmt_quantity(value: float | None, unit: str, digits: int = 3) -> str:
    """'5,818 lamp-s', '0.0547 kWh'; '-' when there is no value."""
    text = fmt_num(value, digits)
    return text if text == "-" else f"{text} {unit}"


def fmt_pct(fraction: float | None, decimals: int = 1) -> str:
    """A fraction as a percentage for people: 0.3470 -> '34.7 %'; '-' when there is none."""
    if fraction is None or (isinstance(fraction, float) and math.isnan(fraction)):
        return "-"
    return f"{100.0 * fraction:,.{decimals}f} %"


def few_objects_text(n_objects: int) -> str:
    """The warning for a run resting on fewer than FEW_OBJECTS objects (one line)."""
    return (f"Few objects: only {n_objects} crossed a lamp zone in this run (fewer than {FEW_OBJECTS}); "
            "every figure here rests on them")  # fmt: skip


def warn_few_objects(fig, n_objects: int | None) -> bool:
    """Write the few-objects warning over the figure when the run rests on too few; True if written.

    Above the title, outside the axes: nothing is drawn there, and the saved PNG's tight bounding
    box grows to take it in.
    """
    if n_objects is None or n_objects >= FEW_OBJECTS:
        return False
    fig.text(0.5, 1.0, few_objects_text(n_objects), ha="center", va="bottom", fontsize=9,
             color=WARNING_COLOR, fontweight="bold", gid="few-objects-warning")  # fmt: skip
    return True


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
