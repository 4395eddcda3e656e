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
