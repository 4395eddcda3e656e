"""Top-down plot of a street: lanes, sidewalks, scenery, lamps, camera footprints, tracks.

``plot_topdown(street, cameras, tracks, path)`` writes a PNG (matplotlib's Agg
backend through a bare ``Figure``, so no global pyplot state). A camera's
footprint is the ground its image border back-projects to (through its lens
distortion), cut at ``FOOTPRINT_RANGE_M`` of forward distance - rays above the
horizon are cut there as well.

With ``coverage`` (``citysim.world.coverage.coverage_grid``) the picture also shows where a
lamp camera sees a person whole within the detector's range (green cells) and where it does not
(red cells), with the blind stretches along the street as red bars on the top edge.

Conventions: world frame of docs/design/architecture.md (x east, y north, m; on the straight
street x runs along it and y across it); tracks are ``{object_id: (T, 2) array of (x_m, y_m)}``.
A street whose centreline bends is drawn in the world: its lanes, sidewalks, coverage cells and
bars follow the centreline (``citysim.report.topdown_curved``); the blind stretches are then
written out in s, metres along the street.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Ellipse, Polygon, Rectangle

from citysim.report import topdown_curved as curved
from citysim.world.coverage import CoverageGrid, blind_stretches_m
from citysim.world.street import Street
from detector.camera import CameraModel

FOOTPRINT_RANGE_M = 50.0
BORDER_SAMPLES_PER_EDGE = 48

#: StaticObject.kind -> face colour on the plot.
SCENERY_COLOURS: dict[str, str] = {
    "wall": "#8c7b6b",
    "building": "#a89f91",
    "hedge": "#4f7942",
    "tree": "#2e8b57",
    "parked_car": "#4a6fa5",
    "pole": "#555555",
}


def camera_footprint_m(camera: CameraModel, range_m: float = FOOTPRINT_RANGE_M) -> np.ndarray:
    """(M, 2) ground polygon (x, y) seen by ``camera``, cut at ``range_m`` forward distance.

    The image border is walked clockwise from the top-left pixel; each border
    pixel's ray (undistorted) meets the ground, or, if it meets it beyond the
    range or not at all (above the horizon), is replaced by the point at the
    range along the ray's bearing. Rays pointing backwards are dropped.
    """
    w, h = camera.width_px, camera.height_px
    n = BORDER_SAMPLES_PER_EDGE
    top = np.column_stack([np.linspace(-0.5, w - 0.5, n), np.full(n, -0.5)])
    right = np.column_stack([np.full(n, w - 0.5), np.linspace(-0.5, h - 0.5, n)])
    bottom = np.column_stack([np.linspace(w - 0.5, -0.5, n), np.full(n, h - 0.5)])
    left = np.column_stack([np.full(n, -0.5), np.linspace(h - 0.5, -0.5, n)])
    border = np.concatenate([top, right, bottom, left])
    und = camera.undistort_pixels(border)
    rays_cam = np.column_stack(
        [
            (und[:, 0] - camera.cx_px) / camera.fx_px,
            (und[:, 1] - camera.cy_px) / camera.fy_px,
            np.ones(len(und)),
        ]
    )
    rays = rays_cam @ camera.rotation_world_to_cam
    foot = camera.position_m[:2]
    heading = camera.heading_unit
    horiz = rays[:, :2]
    along = horiz @ heading
    with np.errstate(divide="ignore", invalid="ignore"):
        s_ground = np.where(rays[:, 2] < 0.0, camera.height_m / -rays[:, 2], np.inf)
        forward_ground = s_ground * along
        s_cap = range_m / along
    s = np.where((forward_ground <= range_m) & np.isfinite(forward_ground), s_ground, s_cap)
    keep = (along > 1e-9) | ((rays[:, 2] < 0.0) & (forward_ground <= range_m))
    return foot + horiz[keep] * s[keep, None]


def plot_topdown(
    street: Street,
    cameras: Sequence[CameraModel],
    tracks: Mapping[int, np.ndarray] | None,
    path: str | Path,
    coverage: CoverageGrid | None = None,
) -> Path:
    """Draw the street from above and write it to ``path`` (PNG); returns the path.

    A street along +x (``Centreline.is_straight_x``) is drawn in x along it and y across it; one
    whose centreline bends is drawn in the world (x east, y north) by ``_plot_curved``."""
    path = Path(path)
    if not street.centreline.is_straight_x:
        return _plot_curved(street, cameras, tracks, path, coverage)
    y_lo, y_hi = street.y_min_m - 6.0, street.y_max_m + 6.0
    span_x = street.length_m + 10.0
    fig = Figure(
        figsize=(min(max(6.0, span_x / 8.0), 24.0), max(3.0, (y_hi - y_lo) / 6.0)), dpi=100
    )
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    ax.set_facecolor("#c9d7b8")  # verge
    # layers in drawing order; each sets its own zorder, so the order only matters for ties
    _draw_sidewalks(ax, street)
    _draw_lanes(ax, street)
    _draw_scenery(ax, street)
    if coverage is not None:
        _draw_coverage(ax, coverage, y_hi)
    _draw_cameras(ax, cameras)
    _draw_lamps(ax, street, y_lo)
    if tracks:
        _draw_tracks(ax, fig, tracks)

    title = f"Street {street.length_m:.0f} m, {len(street.lamps)} lamps, {len(cameras)} cameras"
    if coverage is not None:
        title += f"; {100 * coverage.seen.mean():.0f} % of lanes and sidewalks seen (green), blind in red"
    bounds_m = (-5.0, street.length_m + 5.0, y_lo, y_hi)
    return _finish(fig, ax, path, bounds_m, ("x along the street (m)", "y across (m)"), title)


def _finish(fig: Figure, ax, path: Path, bounds_m: tuple, axis_labels: tuple[str, str], title: str) -> Path:
    """Frame the axes on ``bounds_m`` (x min, x max, y min, y max; m) at equal scale, label and title
    them, and write the figure to ``path`` (PNG); returns the path."""
    ax.set_xlim(bounds_m[0], bounds_m[1])
    ax.set_ylim(bounds_m[2], bounds_m[3])
    ax.set_aspect("equal")
    ax.set_xlabel(axis_labels[0])
    ax.set_ylabel(axis_labels[1])
    ax.set_title(title)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, format="png")
    return path


def _plot_curved(
    street: Street,
    cameras: Sequence[CameraModel],
    tracks: Mapping[int, np.ndarray] | None,
    path: Path,
    coverage: CoverageGrid | None,
) -> Path:
    """``plot_topdown`` of a street whose centreline bends: strips, coverage cells and bars follow the
    centreline (``citysim.report.topdown_curved``), the rest stands where it is in the world; the
    axes span the street's world bounding box at equal scale."""
    bbox = curved.street_bbox_m(street)
    fig = Figure(figsize=curved.figsize_in(bbox), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    ax.set_facecolor("#c9d7b8")  # verge
    curved.draw_strips(ax, street)
    _draw_scenery(ax, street)
    if coverage is not None:
        curved.draw_coverage(ax, coverage, street)
    _draw_cameras(ax, cameras)
    _draw_lamps(ax, street, 0.0, zone_bar=curved.zone_bar_xy(street))
    if tracks:
        _draw_tracks(ax, fig, tracks)
    title = f"Street {street.length_m:.0f} m along its centreline, {len(street.lamps)} lamps, {len(cameras)} cameras"
    if coverage is not None:
        title += f"\n{100 * coverage.seen.mean():.0f} % of lanes and sidewalks seen (green), blind in red"
    return _finish(fig, ax, path, tuple(bbox), ("x east (m)", "y north (m)"), title)


def plot_coverage_map(street: Street, path: str | Path) -> Path:
    """The street's camera coverage from above (``coverage.png`` of a run): fields of view, seen and
    blind ground."""
    from citysim.world.coverage import coverage_grid

    return plot_topdown(street, [site.camera for site in street.cameras], None, path, coverage=coverage_grid(street))


def _draw_sidewalks(ax: Axes, street: Street) -> None:
    for sw in street.sidewalks:
        ax.add_patch(
            Rectangle(
                (0.0, sw.y_center_m - sw.width_m / 2),
                street.length_m,
                sw.width_m,
                color="#d9d4cc",
                zorder=1,
            )
        )


def _draw_lanes(ax: Axes, street: Street) -> None:
    """Lanes with direction arrows, and the line between neighbours (dashed: same direction)."""
    x0, x1 = 0.0, street.length_m
    lanes = sorted(street.lanes, key=lambda lane: lane.y_center_m)
    for lane in lanes:
        ax.add_patch(
            Rectangle(
                (x0, lane.y_center_m - lane.width_m / 2),
                x1 - x0,
                lane.width_m,
                color="#5b5b5b",
                zorder=1,
            )
        )
        for xa in np.arange(x0 + 5.0, x1, 20.0):  # direction arrows
            ax.annotate(
                "",
                xy=(xa + 3.0 * lane.direction, lane.y_center_m),
                xytext=(xa, lane.y_center_m),
                arrowprops={"arrowstyle": "->", "color": "#e8e8e8", "lw": 1.0},
                zorder=2,
            )
    for a, b in zip(lanes[:-1], lanes[1:], strict=True):
        y_line = (a.y_center_m + a.width_m / 2 + b.y_center_m - b.width_m / 2) / 2
        style = "--" if a.direction == b.direction else "-"
        ax.plot([x0, x1], [y_line, y_line], style, color="white", lw=1.0, zorder=2)


def _draw_scenery(ax: Axes, street: Street) -> None:
    for obj in street.scenery:
        colour = SCENERY_COLOURS.get(obj.kind, "#999999")
        if obj.kind == "tree":
            ax.add_patch(
                Ellipse(
                    (obj.x_m, obj.y_m), obj.length_m, obj.width_m, color=colour, alpha=0.8, zorder=3
                )
            )
        else:
            ax.add_patch(
                Rectangle(
                    (obj.x_m - obj.length_m / 2, obj.y_m - obj.width_m / 2),
                    obj.length_m,
                    obj.width_m,
                    color=colour,
                    zorder=3,
                )
            )


def _draw_coverage(ax: Axes, grid: CoverageGrid, y_hi: float) -> None:
    """Seen cells green, unseen cells red; blind stretches of the street as red bars on the top edge.

    The cells are one image on a regular grid (cells off the lanes and sidewalks transparent):
    a patch per cell cost some 30 s of drawing for an 11-lamp street."""
    step = grid.step_m
    y0 = float(grid.ys_m.min()) - step / 2
    n_rows = int(round((float(grid.ys_m.max()) + step / 2 - y0) / step))
    rows = np.clip(np.round((grid.ys_m - y0) / step - 0.5).astype(int), 0, n_rows - 1)
    green, red = np.array((0.18, 0.49, 0.20)), np.array((0.78, 0.16, 0.16))
    rgba = np.zeros((n_rows, len(grid.xs_m), 4))
    rgba[rows, :, :3] = np.where(grid.seen.T[:, :, None], green, red)  # image rows are y
    rgba[rows, :, 3] = 0.30
    x0 = float(grid.xs_m[0]) - step / 2
    extent = (x0, x0 + step * len(grid.xs_m), y0, y0 + step * n_rows)
    ax.imshow(rgba, origin="lower", extent=extent, interpolation="nearest", aspect="auto", zorder=4)
    for a_m, b_m in blind_stretches_m(grid):
        ax.plot([a_m, b_m], [y_hi - 1.0, y_hi - 1.0], lw=5, color="#c62828", solid_capstyle="butt", zorder=9)


def _draw_cameras(ax: Axes, cameras: Sequence[CameraModel]) -> None:
    """Each camera's ground footprint, and a triangle at its pole pointing where it looks."""
    for cam in cameras:
        poly = camera_footprint_m(cam)
        if len(poly) >= 3:
            ax.add_patch(
                Polygon(
                    poly,
                    closed=True,
                    facecolor="#ffd54f",
                    edgecolor="#c79100",
                    alpha=0.25,
                    zorder=4,
                )
            )
        ax.plot(
            [cam.x_m], [cam.y_m], marker=(3, 0, cam.yaw_deg - 90.0), color="#c79100", ms=9, zorder=6
        )


def _draw_lamps(ax: Axes, street: Street, y_lo: float, zone_bar=None) -> None:
    """Lamps as stars with their index, and each lamp's zone as a bar along the bottom edge (at
    ``y_lo + 1`` m), or along the world line ``zone_bar(s0_m, s1_m) -> (xs, ys)`` when given."""
    if not street.lamps:
        return
    ax.scatter(
        [lamp.x_m for lamp in street.lamps],
        [lamp.y_m for lamp in street.lamps],
        marker="*",
        s=140,
        color="#ffeb3b",
        edgecolors="black",
        linewidths=0.6,
        zorder=7,
        label="lamp",
    )
    for lamp in street.lamps:
        if zone_bar is None:
            ax.plot([lamp.zone_start_m, lamp.zone_end_m], [y_lo + 1.0, y_lo + 1.0], lw=3, zorder=5)
        else:
            ax.plot(*zone_bar(lamp.zone_start_m, lamp.zone_end_m), lw=3, zorder=5, gid="zone")
        ax.annotate(
            str(lamp.index),
            (lamp.x_m, lamp.y_m),
            xytext=(4, 4),
            textcoords="offset points",
            fontsize=7,
        )


def _draw_tracks(ax: Axes, fig: Figure, tracks: Mapping[int, np.ndarray]) -> None:
    """Each object's path, a dot where it starts and its id where it ends."""
    colours = fig.colormaps["tab10"] if hasattr(fig, "colormaps") else None
    for k, (object_id, xy) in enumerate(sorted(tracks.items())):
        pts = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        if len(pts) == 0:
            continue
        colour = colours(k % 10) if colours is not None else None
        ax.plot(pts[:, 0], pts[:, 1], "-", lw=1.2, color=colour, zorder=8)
        ax.plot(pts[0, 0], pts[0, 1], "o", ms=3, color=colour, zorder=8)
        ax.annotate(str(object_id), pts[-1], fontsize=6, color=colour, zorder=8)
