"""The top-down plot of a bent street follows its centreline; a straight street draws as it always has.

curved_bend's centreline runs (0, 0) -> (180, 0) -> (180, 180): a 90-degree left bend at s = 180 m.
Its sidewalks span d in [3.2, 5.4] and [-5.4, -3.2] m, its lanes [0, 3.2] and [-3.2, 0] m. At the
bend the cross-section is the mitre (-1, 1), so the point d to the left of the vertex is
(180 - d, d); on the second leg a point (s, d) is (180 - d, s - 180).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from matplotlib.image import AxesImage
from matplotlib.patches import Polygon, Rectangle

from citysim.config.scenario import load_scenario
from citysim.report.topdown import plot_coverage_map, plot_topdown
from citysim.world.coverage import blind_stretches_m, coverage_grid
from citysim.world.street import build_street

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def bend():
    return build_street(load_scenario(ROOT / "scenarios" / "curved_bend.yaml"))


@pytest.fixture()
def drawn(monkeypatch):
    """Collects every figure ``savefig`` writes (and still writes it)."""
    figures: list[Figure] = []
    save = Figure.savefig

    def keep(fig, *args, **kwargs):
        figures.append(fig)
        return save(fig, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", keep)
    return figures


def _near(points: np.ndarray, target: tuple[float, float], tol_m: float = 0.5) -> bool:
    return bool(np.min(np.hypot(*(points - np.asarray(target)).T)) <= tol_m)


@pytest.mark.parametrize(
    ("gid", "d_lo_m", "d_hi_m", "hand_points"),
    [
        # right sidewalk: its outer edge at the start, half-way along the first leg, at the bend
        # (outside of the turn: (180 + 5.4, -5.4)), on the second leg at s = 300 m
        ("sidewalk", -5.4, -3.2, [(0.0, -5.4), (100.0, -5.4), (185.4, -5.4), (185.4, 120.0)]),
        # left sidewalk: inside of the turn (174.6, 5.4), its outer edge at the end (174.6, 180)
        (
            "sidewalk",
            3.2,
            5.4,
            [(174.6, 5.4), (176.8, 3.2), (174.6, 180.0), (176.8, 300.0 - 180.0)],
        ),
        ("lane", -3.2, 0.0, [(183.2, -3.2), (180.0, 0.0), (183.2, 90.0)]),
        ("lane", 0.0, 3.2, [(176.8, 3.2), (176.8, 120.0), (50.0, 3.2)]),
    ],
)
def test_strips_follow_the_centreline_offsets(
    bend, drawn, tmp_path, gid, d_lo_m, d_hi_m, hand_points
) -> None:
    plot_topdown(bend, [], None, tmp_path / "bend.png")
    ax = drawn[-1].axes[0]
    polys = [p.get_xy() for p in ax.patches if isinstance(p, Polygon) and p.get_gid() == gid]
    assert len(polys) == 2
    line = bend.centreline
    # the polygon of this strip: the one whose vertices lie on its two edges
    matches = []
    for xy in polys:
        s, d = line.to_sd(xy[:, 0], xy[:, 1])
        on_edge = np.minimum(np.abs(d - d_lo_m), np.abs(d - d_hi_m)) <= 0.5
        if on_edge.all():
            matches.append((xy, s))
    assert len(matches) == 1, f"no {gid} polygon on d = {d_lo_m} .. {d_hi_m} m"
    xy, s = matches[0]
    assert s.min() == pytest.approx(0.0, abs=0.5) and s.max() == pytest.approx(
        bend.length_m, abs=0.5
    )
    assert np.max(np.diff(np.sort(np.unique(np.round(s, 6))))) <= 1.0 + 1e-9  # sampled every <= 1 m
    for point in hand_points:
        assert _near(xy, point), f"{gid} misses the hand-computed point {point}"


def test_the_lane_line_is_the_centreline(bend, drawn, tmp_path) -> None:
    plot_topdown(bend, [], None, tmp_path / "bend.png")
    lines = [ln for ln in drawn[-1].axes[0].lines if ln.get_gid() == "lane line"]
    assert len(lines) == 1
    xy = lines[0].get_xydata()
    assert (
        _near(xy, (180.0, 0.0), 1e-6)
        and _near(xy, (0.0, 0.0), 1e-6)
        and _near(xy, (180.0, 180.0), 1e-6)
    )
    on_leg = (np.abs(xy[:, 1]) <= 1e-6) | (np.abs(xy[:, 0] - 180.0) <= 1e-6)
    assert on_leg.all()


def test_axes_hold_every_lamp_and_the_whole_centreline_at_equal_scale(
    bend, drawn, tmp_path
) -> None:
    tracks = {7: np.column_stack([np.full(50, 178.0), np.linspace(-20.0, 150.0, 50)])}
    plot_topdown(bend, [s.camera for s in bend.cameras], tracks, tmp_path / "topdown.png")
    ax = drawn[-1].axes[0]
    (x_lo, x_hi), (y_lo, y_hi) = ax.get_xlim(), ax.get_ylim()
    pts = np.vstack(
        [np.asarray(bend.centreline.points_m), [(lamp.x_m, lamp.y_m) for lamp in bend.lamps]]
    )
    assert np.all((pts[:, 0] > x_lo) & (pts[:, 0] < x_hi) & (pts[:, 1] > y_lo) & (pts[:, 1] < y_hi))
    assert ax.get_aspect() == 1.0
    assert (
        x_hi - x_lo < 230.0 and y_hi - y_lo < 230.0
    )  # the bend's box (~192 m), not 360 m of straight
    assert ax.get_xlabel() == "x east (m)"
    assert (tmp_path / "topdown.png").stat().st_size > 10_000


def test_coverage_cells_and_blind_stretches_stand_in_the_world(bend, drawn, tmp_path) -> None:
    grid = coverage_grid(bend)
    plot_coverage_map(bend, tmp_path / "coverage.png")
    ax = drawn[-1].axes[0]
    (cells,) = [
        c
        for c in ax.collections
        if isinstance(c, PolyCollection) and len(c.get_paths()) == grid.seen.size
    ]
    centres = np.array([p.vertices[:4].mean(axis=0) for p in cells.get_paths()])
    s, d = np.meshgrid(grid.xs_m, grid.ys_m, indexing="ij")
    wx, wy = bend.centreline.to_xy(s.ravel(), d.ravel())
    assert np.max(np.hypot(centres[:, 0] - wx, centres[:, 1] - wy)) <= 0.5
    red = cells.get_facecolors()[:, 0] > 0.5
    assert np.array_equal(red, ~grid.seen.ravel())
    stretches = blind_stretches_m(grid)
    assert stretches  # curved_bend has blind ground between its cameras
    bars = [ln.get_xydata() for ln in ax.lines if ln.get_gid() == "blind"]
    assert len(bars) == len(stretches)
    for (a_m, b_m), xy in zip(stretches, bars, strict=True):
        bs, bd = bend.centreline.to_sd(xy[:, 0], xy[:, 1])
        assert bs.min() == pytest.approx(a_m, abs=0.5) and bs.max() == pytest.approx(b_m, abs=0.5)
        assert np.all(bd > bend.y_max_m)  # outside the left-most strip
    (caption,) = [t.get_text() for t in ax.texts if "blind along the street (s, m)" in t.get_text()]
    assert f"{stretches[0][0]:.0f}-{stretches[0][1]:.0f}" in caption


def test_a_straight_street_draws_its_bands_as_before(drawn, tmp_path) -> None:
    """suburban_night keeps the straight drawing: rectangles from x = 0 to length_m, an image of the
    coverage in x, y, the limits and labels of the x-along-the-street frame, nothing of the bent one."""
    street = build_street(load_scenario(ROOT / "scenarios" / "suburban_night.yaml"))
    grid = coverage_grid(street)
    plot_coverage_map(street, tmp_path / "coverage.png")
    ax = drawn[-1].axes[0]
    rects = sorted((r.get_y(), r.get_height()) for r in ax.patches
                   if isinstance(r, Rectangle) and r.get_x() == 0.0 and r.get_width() == street.length_m)  # fmt: skip
    bands = sorted(
        (b.y_center_m - b.width_m / 2, b.width_m) for b in (*street.lanes, *street.sidewalks)
    )
    assert rects == bands
    assert not [
        a
        for a in (*ax.patches, *ax.lines)
        if a.get_gid() in {"sidewalk", "lane", "lane line", "blind", "zone"}
    ]
    assert ax.get_xlim() == (-5.0, street.length_m + 5.0)
    assert ax.get_ylim() == (street.y_min_m - 6.0, street.y_max_m + 6.0)
    assert ax.get_xlabel() == "x along the street (m)"
    (image,) = [im for im in ax.get_images() if isinstance(im, AxesImage)]
    x0 = float(grid.xs_m[0]) - grid.step_m / 2
    assert image.get_extent()[:2] == pytest.approx([x0, x0 + grid.step_m * len(grid.xs_m)])
    assert not ax.texts or all("blind along" not in t.get_text() for t in ax.texts)
