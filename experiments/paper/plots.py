"""Figures of the reproduction, drawn like the paper's Fig. 9 and Fig. 10 (small PNGs).

``plot_confusions``: row-normalised confusion matrices, binary and 5-class,
night and day (darker = larger, as in the paper). ``plot_precision_recall``:
(a) binary PR curves night and day, (b) night and (c) day per class with the
micro average. Figures are written with matplotlib's Agg canvas (no display).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from detector.classes import CLASSES
from experiments.paper.metrics import BINARY_CLASSES, Confusions, PrecisionRecall

#: The paper's axis letters (Fig. 9): N noise, P pedestrian, G group, C cyclist, V vehicle, T target.
LETTERS = {
    "noise": "N",
    "pedestrian": "P",
    "group": "G",
    "cyclist": "C",
    "vehicle": "V",
    "target": "T",
}
CLASS_COLOURS = {"noise": "#7f7f7f", "pedestrian": "#1f77b4", "group": "#2ca02c",
                 "cyclist": "#ff7f0e", "vehicle": "#d62728"}  # fmt: skip
DPI = 72


def _save(fig: Figure, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    FigureCanvasAgg(fig)
    fig.savefig(path, dpi=DPI)
    return path


def _matrix(ax, rates: np.ndarray, counts: np.ndarray, labels: tuple[str, ...], title: str) -> None:
    ax.imshow(rates, cmap="Greys", vmin=0.0, vmax=1.0)
    letters = [LETTERS[c] for c in labels]
    ax.set_xticks(range(len(labels)), letters)
    ax.set_yticks(range(len(labels)), letters)
    ax.set_xlabel("predicted")
    ax.set_ylabel("truth")
    ax.set_title(title, fontsize=10)
    for i in range(len(labels)):
        for j in range(len(labels)):
            if counts[i].sum() == 0:
                text, colour = "-", "black"
            else:
                text, colour = f"{rates[i, j]:.2f}", "white" if rates[i, j] > 0.55 else "black"
            ax.text(j, i, text, ha="center", va="center", fontsize=8, color=colour)


def plot_confusions(night: Confusions, day: Confusions, path: Path) -> Path:
    """Fig. 9: (a) night and (b) day binary, (c) night and (d) day 5-class, row-normalised."""
    fig = Figure(figsize=(9.0, 8.0))
    axes = fig.subplots(2, 2)
    _matrix(
        axes[0, 0], night.binary, night.binary_counts, BINARY_CLASSES, "(a) night, target vs noise"
    )
    _matrix(axes[0, 1], day.binary, day.binary_counts, BINARY_CLASSES, "(b) day, target vs noise")
    _matrix(axes[1, 0], night.five, night.five_counts, CLASSES, "(c) night, 5 classes")
    _matrix(axes[1, 1], day.five, day.five_counts, CLASSES, "(d) day, 5 classes")
    fig.tight_layout()
    return _save(fig, path)


def _ap_label(name: str, ap: float | None) -> str:
    return f"{name} (AP {ap:.2f})" if ap is not None else f"{name} (absent)"


def _pr_panel(ax, pr: PrecisionRecall, title: str) -> None:
    for cls, curve in pr.per_class.items():
        if curve.recall.size:
            ax.step(curve.recall, curve.precision, where="post", color=CLASS_COLOURS[cls],
                    lw=1.2, label=_ap_label(cls, curve.ap))  # fmt: skip
    if pr.micro.recall.size:
        ax.step(pr.micro.recall, pr.micro.precision, where="post", color="black", ls="--", lw=1.2,
                label=_ap_label("micro avg", pr.micro.ap))  # fmt: skip
    macro = f"macro mAP {pr.macro_ap:.2f}" if pr.macro_ap is not None else "macro mAP -"
    ax.set_title(f"{title}\n{macro}", fontsize=10)
    _axes(ax)


def _axes(ax) -> None:
    ax.set_xlim(0.0, 1.0)
    ax.set_ylim(0.0, 1.02)
    ax.set_xlabel("recall")
    ax.set_ylabel("precision")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="lower left")


def plot_precision_recall(
    night: PrecisionRecall,
    day: PrecisionRecall,
    path: Path,
    night_regions: PrecisionRecall | None = None,
    day_regions: PrecisionRecall | None = None,
) -> Path:
    """Fig. 10: (a) binary night and day, (b) night and (c) day per class with micro average.

    With ``*_regions`` the binary panel also shows, dashed, the curves over the
    segmented regions only (missed objects left out).
    """
    fig = Figure(figsize=(13.5, 4.6))
    axes = fig.subplots(1, 3)
    ax = axes[0]
    for name, pr, regions, colour in (("night", night, night_regions, "#1f3a93"),
                                      ("day", day, day_regions, "#e08e0b")):  # fmt: skip
        b = pr.binary
        if b.recall.size:
            ax.step(
                b.recall,
                b.precision,
                where="post",
                color=colour,
                lw=1.4,
                label=_ap_label(name, b.ap),
            )
        if regions is not None and regions.binary.recall.size:
            r = regions.binary
            ax.step(r.recall, r.precision, where="post", color=colour, lw=1.0, ls="--",
                    label=_ap_label(f"{name}, regions only", r.ap))  # fmt: skip
    ax.set_title("(a) target vs noise, P(target)", fontsize=10)
    _axes(ax)
    _pr_panel(axes[1], night, "(b) night, per class")
    _pr_panel(axes[2], day, "(c) day, per class")
    fig.tight_layout()
    return _save(fig, path)
