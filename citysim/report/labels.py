"""Point labels that do not overprint: greedy placement around each point, leader lines when moved.

Used by the frontier, where eleven controllers can crowd one corner. Boxes are measured in the
rendered figure (display pixels), so the rule holds for whatever font and size the figure uses.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from matplotlib.text import Text
from matplotlib.transforms import Bbox

#: Distances from the point tried in turn, typographic points; beyond the first a leader line is drawn.
RINGS_PT = (7.0, 16.0, 28.0, 42.0, 58.0, 76.0)
#: Directions tried at each distance, degrees counter-clockwise from east (east first: a label reads
#: best to the right of its point).
ANGLES_DEG = (30, -30, 90, -90, 150, -150, 0, 180, 60, -60, 120, -120)
#: Clearance kept between boxes, display pixels.
GAP_PX = 2.0
#: Half the side of the square a point's marker is taken to cover, display pixels.
MARKER_HALF_PX = 5.0


@dataclass(frozen=True)
class Label:
    """One label to place: its text, the point it names (data coordinates) and its colour."""

    text: str
    x: float
    y: float
    color: str = "black"


def _alignment(angle_deg: float) -> tuple[str, str]:
    """(ha, va) that put the box on the side of the point the direction points to."""
    dx, dy = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    ha = "left" if dx > 0.3 else "right" if dx < -0.3 else "center"
    va = "bottom" if dy > 0.3 else "top" if dy < -0.3 else "center"
    return ha, va


def _overlap_px2(box: Bbox, others: Sequence[Bbox]) -> float:
    """Summed overlap area of ``box`` (grown by GAP_PX) with ``others``, square display pixels."""
    grown = box.padded(GAP_PX)
    total = 0.0
    for other in others:
        w = min(grown.x1, other.x1) - max(grown.x0, other.x0)
        h = min(grown.y1, other.y1) - max(grown.y0, other.y0)
        if w > 0 and h > 0:
            total += w * h
    return total


def _outside_px2(box: Bbox, frame: Bbox) -> float:
    """Area of ``box`` outside ``frame`` (the axes), square display pixels."""
    w = max(0.0, min(box.x1, frame.x1) - max(box.x0, frame.x0))
    h = max(0.0, min(box.y1, frame.y1) - max(box.y0, frame.y0))
    return box.width * box.height - w * h


def place_labels(ax, labels: Sequence[Label], fontsize: float = 7.0) -> list[Text]:
    """Annotate each point of ``labels`` on ``ax`` where its box overlaps no placed box, no point's
    marker, the legend or a text already on the axes, and stays inside the axes; a label moved past the nearest ring gets a thin leader line.

    Call it after the axes' limits are final (the boxes are measured in display pixels). Labels are
    placed in the given order; one with no free spot takes the candidate of least overlap.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes holding the points (data coordinates).
    labels : sequence of Label
        Text, point (data coordinates) and colour of each label.
    fontsize : float
        Label size, typographic points.

    Returns
    -------
    list of matplotlib.text.Annotation
        The labels drawn, in the order given.
    """
    fig = ax.figure
    renderer = fig.canvas.get_renderer()
    frame = ax.get_window_extent(renderer)
    markers = []
    for label in labels:
        px, py = ax.transData.transform((label.x, label.y))
        markers.append(Bbox.from_extents(px - MARKER_HALF_PX, py - MARKER_HALF_PX, px + MARKER_HALF_PX,
                                         py + MARKER_HALF_PX))  # fmt: skip
    legend = ax.get_legend()
    # the legend and the axes' texts already drawn (the frontier's "ideal") are kept clear too
    placed: list[Bbox] = [t.get_window_extent(renderer) for t in ax.texts]
    if legend is not None:
        placed.append(legend.get_window_extent(renderer))
    drawn = []
    for i, label in enumerate(labels):
        ann = ax.annotate(label.text, (label.x, label.y), textcoords="offset points", xytext=(0.0, 0.0),
                          fontsize=fontsize, color=label.color, zorder=4)  # fmt: skip
        best: tuple[float, int, float, float, Bbox] | None = None
        others = [m for j, m in enumerate(markers) if j != i]
        for ring, radius in enumerate(RINGS_PT):
            for angle in ANGLES_DEG:
                ha, va = _alignment(angle)
                ann.set_horizontalalignment(ha)
                ann.set_verticalalignment(va)
                ann.xyann = (radius * math.cos(math.radians(angle)), radius * math.sin(math.radians(angle)))
                ann.update_positions(renderer)  # an offset text is placed at draw time otherwise
                box = Text.get_window_extent(ann, renderer)
                cost = _overlap_px2(box, placed + others) + _outside_px2(box, frame) + _overlap_px2(box, [markers[i]])
                if best is None or cost < best[0]:
                    best = (cost, ring, angle, radius, box)
                if cost == 0.0:
                    break
            if best is not None and best[0] == 0.0:
                break
        _cost, ring, angle, radius, box = best
        ann.remove()  # the probe; the label is drawn anew, with its leader line when moved
        ha, va = _alignment(angle)
        offset = (radius * math.cos(math.radians(angle)), radius * math.sin(math.radians(angle)))
        leader = None if ring == 0 else {"arrowstyle": "-", "color": label.color, "lw": 0.6, "alpha": 0.7,
                                         "shrinkA": 1.0, "shrinkB": 3.0}  # fmt: skip
        drawn.append(ax.annotate(label.text, (label.x, label.y), textcoords="offset points", xytext=offset,
                                 ha=ha, va=va, fontsize=fontsize, color=label.color, zorder=4,
                                 arrowprops=leader))  # fmt: skip
        placed.append(box)
    return drawn
