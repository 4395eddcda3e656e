"""Drawing a street whose centreline bends: its strips, coverage cells and bars placed in the world.

Everything the street defines in street coordinates (s metres along ``Street.centreline`` from its
first point, d metres to its left) is sampled along s about every ``SAMPLE_STEP_M`` and moved to the
world (x east, y north, m) through ``Centreline.to_xy``; things that already stand in the world
(lamps, cameras, scenery, tracks) are drawn where they stand by ``citysim.report.topdown``.
"""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import PolyCollection
from matplotlib.patches import Polygon

from citysim.world.centreline import Centreline
from citysim.world.coverage import CoverageGrid, blind_stretches_m
from citysim.world.street import Street

#: Spacing of the samples along s of every strip and bar, m (at most).
SAMPLE_STEP_M = 1.0
#: Margin round the street's world bounding box, m.
MARGIN_M = 6.0
#: The blind-stretch bars (left) and lamp-zone bars (right) stand this far outside the outermost
#: strips, m: clear of poles standing at the kerb.
BAR_OFFSET_M = 3.0


def samples_s_m(s0_m: float, s1_m: float, step_m: float = SAMPLE_STEP_M) -> np.ndarray:
    """s from ``s0_m`` to ``s1_m`` inclusive at most ``step_m`` apart (m)."""
    n = max(2, int(np.ceil(abs(s1_m - s0_m) / step_m)) + 1)
    return np.linspace(s0_m, s1_m, n)


def offset_line_xy(line: Centreline, s0_m: float, s1_m: float, d_m: float) -> np.ndarray:
    """(N, 2) world (x, y) m of the line ``d_m`` left of the centreline from s = ``s0_m`` to ``s1_m``."""
    s = samples_s_m(s0_m, s1_m)
    x, y = line.to_xy(s, np.full_like(s, d_m))
    return np.column_stack([x, y])


def band_polygon_xy(
    line: Centreline, s0_m: float, s1_m: float, d_lo_m: float, d_hi_m: float
) -> np.ndarray:
    """(M, 2) world (x, y) m outline of the strip d in [``d_lo_m``, ``d_hi_m``] between s0 and s1:
    its right edge forward, then its left edge back."""
    right = offset_line_xy(line, s0_m, s1_m, d_lo_m)
    left = offset_line_xy(line, s0_m, s1_m, d_hi_m)
    return np.vstack([right, left[::-1]])


def street_bbox_m(street: Street) -> tuple[float, float, float, float]:
    """(x_lo, x_hi, y_lo, y_hi) world m: the outermost strips' edges over the whole centreline, the
    lamps and the scenery, with ``MARGIN_M`` round them."""
    line = street.centreline
    pts = [offset_line_xy(line, 0.0, street.length_m, d) for d in (street.y_min_m, street.y_max_m)]
    pts.append(np.asarray(line.points_m, dtype=np.float64))
    pts.append(np.array([(lamp.x_m, lamp.y_m) for lamp in street.lamps]).reshape(-1, 2))
    pts.append(np.array([(o.x_m, o.y_m) for o in street.scenery]).reshape(-1, 2))
    xy = np.vstack(pts)
    lo, hi = xy.min(axis=0) - MARGIN_M, xy.max(axis=0) + MARGIN_M
    return float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1])


def figsize_in(bbox: tuple[float, float, float, float]) -> tuple[float, float]:
    """Figure (width, height) inches for a world box: about 8 m per inch on the longer side, that
    side between 6 and 16 inches, the other in proportion (at least 3)."""
    span_x, span_y = bbox[1] - bbox[0], bbox[3] - bbox[2]
    longer = min(max(6.0, max(span_x, span_y) / 8.0), 16.0)
    scale = longer / max(span_x, span_y)
    return max(3.0, span_x * scale), max(3.0, span_y * scale)


def draw_strips(ax: Axes, street: Street) -> None:
    """Sidewalks and lanes as polygons following the centreline, a direction arrow every 20 m of
    each lane, and the line between neighbouring lanes (dashed: same direction)."""
    line, length = street.centreline, street.length_m
    for sw in street.sidewalks:
        half = sw.width_m / 2
        poly = band_polygon_xy(line, 0.0, length, sw.y_center_m - half, sw.y_center_m + half)
        ax.add_patch(Polygon(poly, closed=True, color="#d9d4cc", zorder=1, gid="sidewalk"))
    lanes = sorted(street.lanes, key=lambda lane: lane.y_center_m)
    for lane in lanes:
        half = lane.width_m / 2
        poly = band_polygon_xy(line, 0.0, length, lane.y_center_m - half, lane.y_center_m + half)
        ax.add_patch(Polygon(poly, closed=True, color="#5b5b5b", zorder=1, gid="lane"))
        for sa in np.arange(5.0, length, 20.0):
            tail = line.to_xy(float(sa), lane.y_center_m)
            head = line.to_xy(float(sa) + 3.0 * lane.direction, lane.y_center_m)
            ax.annotate("", xy=head, xytext=tail, zorder=2,
                        arrowprops={"arrowstyle": "->", "color": "#e8e8e8", "lw": 1.0})  # fmt: skip
    for a, b in zip(lanes[:-1], lanes[1:], strict=True):
        d_line = (a.y_center_m + a.width_m / 2 + b.y_center_m - b.width_m / 2) / 2
        xy = offset_line_xy(line, 0.0, length, d_line)
        style = "--" if a.direction == b.direction else "-"
        ax.plot(xy[:, 0], xy[:, 1], style, color="white", lw=1.0, zorder=2, gid="lane line")


def draw_coverage(ax: Axes, grid: CoverageGrid, street: Street) -> None:
    """The coverage grid's cells (laid out in s, d) as world quadrilaterals, seen green and unseen
    red; the blind stretches as red bars ``BAR_OFFSET_M`` outside the left-most strip, and their s intervals
    written in the top-left corner."""
    line, half = street.centreline, grid.step_m / 2
    s, d = np.meshgrid(grid.xs_m, grid.ys_m, indexing="ij")
    s, d = s.ravel(), d.ravel()
    corners = [
        line.to_xy(s + ds, d + dd)
        for ds, dd in ((-half, -half), (half, -half), (half, half), (-half, half))
    ]
    quads = np.stack([np.column_stack(c) for c in corners], axis=1)  # (cells, 4, 2)
    green, red = np.array((0.18, 0.49, 0.20, 0.30)), np.array((0.78, 0.16, 0.16, 0.30))
    colours = np.where(grid.seen.ravel()[:, None], green, red)
    ax.add_collection(PolyCollection(quads, facecolors=colours, edgecolors="none", zorder=4))
    stretches = blind_stretches_m(grid)
    for a_m, b_m in stretches:
        xy = offset_line_xy(line, a_m, b_m, street.y_max_m + BAR_OFFSET_M)
        ax.plot(
            xy[:, 0], xy[:, 1], lw=5, color="#c62828", solid_capstyle="butt", zorder=9, gid="blind"
        )
    text = ", ".join(f"{a:.0f}-{b:.0f}" for a, b in stretches) or "none"
    ax.text(0.01, 0.99, f"blind along the street (s, m): {text}", transform=ax.transAxes, ha="left",
            va="top", fontsize=8, color="#c62828", zorder=10,
            bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "none"})  # fmt: skip


def zone_bar_xy(street: Street):
    """A function (s0_m, s1_m) -> (xs, ys) world m of a lamp zone's bar: the zone's stretch of the
    line ``BAR_OFFSET_M`` outside the right-most strip."""
    d_m = street.y_min_m - BAR_OFFSET_M

    def bar(s0_m: float, s1_m: float) -> tuple[np.ndarray, np.ndarray]:
        xy = offset_line_xy(street.centreline, s0_m, s1_m, d_m)
        return xy[:, 0], xy[:, 1]

    return bar
