"""The top-down plot is written and shows the street; camera footprints are where the camera looks."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from citysim.report.topdown import FOOTPRINT_RANGE_M, camera_footprint_m, plot_topdown
from citysim.world.street import LampSite, Lane, Sidewalk, StaticObject, Street
from tests.citysim.render.test_camera import PINHOLE as CAMERA


def street() -> Street:
    lamps = tuple(
        LampSite(i, x, 6.8, 6.0, CAMERA.placed(x_m=x, y_m=6.8, yaw_deg=yaw), x - 15.0, x + 15.0)
        for i, (x, yaw) in enumerate(((15.0, -10.0), (45.0, 190.0)))
    )
    return Street(
        60.0,
        (Lane(-1.75, 3.5, -1), Lane(1.75, 3.5, 1)),
        (Sidewalk(-5.0, 3.0), Sidewalk(5.0, 3.0)),
        lamps,
        (
            StaticObject("tree", 30.0, 8.0, 3.0, 3.0, 6.0, 0.5),
            StaticObject("wall", 30.0, -8.0, 60.0, 0.3, 2.0, 0.5),
        ),
    )


def test_plot_writes_a_png_with_the_street_and_tracks(tmp_path) -> None:
    st = street()
    tracks = {
        1: np.column_stack([np.linspace(0.0, 60.0, 40), np.full(40, 4.5)]),
        2: np.column_stack([np.linspace(60.0, 0.0, 40), np.full(40, -1.75)]),
    }
    out = plot_topdown(
        st, [lamp.camera for lamp in st.lamps], tracks, tmp_path / "plots" / "street.png"
    )
    assert out.exists() and out.stat().st_size > 10_000
    img = cv2.imread(str(out))
    assert img is not None and img.shape[0] > 100 and img.shape[1] > 300
    colours = np.unique(img.reshape(-1, 3) // 16, axis=0)
    assert len(colours) > 20  # lanes, sidewalks, verge, footprints, tracks: not a blank canvas

    bare = plot_topdown(st, [], None, tmp_path / "bare.png")
    assert bare.stat().st_size < out.stat().st_size  # the tracks and footprints drew something


def test_footprint_lies_ahead_of_the_camera_and_within_range() -> None:
    cam = CAMERA.placed(x_m=10.0, y_m=2.0, yaw_deg=30.0)
    poly = camera_footprint_m(cam)
    fwd_lat = cam.forward_and_lateral_m(poly)
    assert len(poly) >= 3
    assert np.all(fwd_lat[:, 0] > 0.0)
    assert fwd_lat[:, 0].max() == pytest.approx(
        FOOTPRINT_RANGE_M, rel=1e-6
    )  # the horizon is in view: cut
    # the image centre's ground point falls inside the footprint
    centre = cam.ground_point(cam.cx_px, cam.cy_px)[:2]
    assert cv2.pointPolygonTest(poly.astype(np.float32), tuple(map(float, centre)), False) > 0
    # nearest edge: the bottom image row, h / tan(bottom depression) ahead
    near_m = cam.height_m / math.tan(math.radians(cam.bottom_row_depression_deg))
    assert fwd_lat[:, 0].min() == pytest.approx(near_m, rel=0.02)


def test_steep_camera_footprint_is_closed_without_the_range_cut() -> None:
    cam = CAMERA.placed(tilt_deg=70.0)
    fwd = cam.forward_and_lateral_m(camera_footprint_m(cam))[:, 0]
    assert fwd.max() < 10.0  # looking almost straight down: no ray reaches the horizon


def _red_px(path) -> int:
    """Pixels of the plot's 'unseen' red (RGB (198, 40, 40), alone or blended over the street):
    red above green and blue, green and blue alike (which tells it from the zone bars' orange)."""
    bgr = cv2.imread(str(path)).astype(int)
    b, g, r = bgr[..., 0], bgr[..., 1], bgr[..., 2]
    return int(((r - g > 30) & (abs(g - b) < 20)).sum())


def test_coverage_is_drawn_seen_green_and_blind_red(tmp_path) -> None:
    from citysim.world.coverage import CoverageGrid, blind_stretches_m, coverage_grid

    st = street()
    real = coverage_grid(st)
    assert 0.0 < real.seen.mean() < 1.0  # this street has both: the test below can tell them apart
    cams = [lamp.camera for lamp in st.lamps]
    all_seen = CoverageGrid(real.xs_m, real.ys_m, np.ones_like(real.seen), real.step_m, real.end_m)
    none_seen = CoverageGrid(real.xs_m, real.ys_m, np.zeros_like(real.seen), real.step_m, real.end_m)
    assert blind_stretches_m(all_seen) == ()
    assert blind_stretches_m(none_seen) == ((real.xs_m[0] - real.step_m / 2, real.end_m),)
    red = {name: _red_px(plot_topdown(st, cams, None, tmp_path / f"{name}.png", coverage=grid))
           for name, grid in (("all", all_seen), ("real", real), ("none", none_seen))}  # fmt: skip
    # the plot without blind cells has (next to) none of that red; more blind cells, more red
    assert red["all"] < 0.05 * red["none"]
    assert red["all"] < red["real"] < red["none"]
