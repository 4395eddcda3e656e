"""RegionGeometry: the per-camera constants of eqs. 1-11, its plain-Python and vectorised paths."""

from __future__ import annotations

import numpy as np
import pytest

from detector.camera import CameraModel
from detector.features import (
    SCALAR_MAX_REGIONS,
    RegionGeometry,
    estimated_height_m,
    estimated_width_m,
    region_features,
)
from tests.detector.cameras import scene_b


def camera(**overrides) -> CameraModel:
    """The scene B camera tilted only 8 deg."""
    return scene_b(**{"tilt_deg": 8.0, **overrides})


def random_boxes(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    xy = rng.integers((0, 0), (280, 160), (n, 2))
    wh = rng.integers(1, (40, 60), (n, 2))
    boxes = np.column_stack([xy, wh]).astype(np.int32)
    return boxes, rng.uniform(0.2, 1.0, n) * wh[:, 0] * wh[:, 1]


@pytest.mark.parametrize("distortion", [{}, {"k1": -0.08, "k2": 0.01, "p1": 1e-3}])
def test_plain_python_rows_equal_the_vectorised_features(distortion):
    cam = camera(**distortion)
    geometry = RegionGeometry(cam)
    assert 0 < cam.horizon_row_px < cam.height_px  # some boxes end above the horizon
    rng = np.random.default_rng(1)
    n_valid = []
    for n in (1, 5, SCALAR_MAX_REGIONS, SCALAR_MAX_REGIONS + 9):
        boxes, areas = random_boxes(rng, n)
        feats, valid = geometry.features(boxes, areas)
        rows = geometry.rows(boxes.tolist(), areas.tolist())
        assert [r is not None for r in rows] == valid.tolist()
        n_valid.append(int(valid.sum()))
        got = np.array([r if r is not None else [np.nan] * 6 for r in rows])
        np.testing.assert_allclose(got, feats, rtol=1e-12, atol=1e-12)
    assert 0 < sum(n_valid) < 2 * SCALAR_MAX_REGIONS + 15  # both kinds of region met


def test_vectorised_features_follow_the_camera_equations():
    cam = camera(k1=-0.05)
    boxes, areas = random_boxes(np.random.default_rng(2), 40)
    feats, valid = region_features(cam, boxes, areas)
    x, y, w, h = boxes.T.astype(np.float64)
    bl = cam.undistort_pixels(np.column_stack([x - 0.5, y + h - 0.5]))
    br = cam.undistort_pixels(np.column_stack([x + w - 0.5, y + h - 0.5]))
    tc = cam.undistort_pixels(np.column_stack([x + w / 2 - 0.5, y - 0.5]))
    v_bottom = (bl[:, 1] + br[:, 1]) / 2
    distance = cam.forward_distance_m(v_bottom)
    np.testing.assert_array_equal(valid, np.isfinite(distance))
    height = estimated_height_m(cam, distance, tc[:, 1])
    width = estimated_width_m(cam, v_bottom, bl[:, 0], br[:, 0])
    want = np.column_stack(
        [
            width,
            height,
            areas * height * width / (w * h),
            distance,
            np.full(40, cam.tilt_deg),
            np.full(40, cam.height_m),
        ]
    )
    np.testing.assert_allclose(feats[valid], want[valid], rtol=1e-12)
    assert np.isnan(feats[~valid]).all()


def test_one_undistortion_call_matches_the_camera():
    cam = camera(k1=-0.1, k2=0.02, p2=2e-3)
    uv = np.random.default_rng(3).uniform((0, 0), (320, 240), (50, 2))
    np.testing.assert_array_equal(RegionGeometry(cam).undistort(uv), cam.undistort_pixels(uv))


@pytest.mark.parametrize("distortion", [{"k1": -0.05}, {"k1": -0.08, "k2": 0.01, "p1": 1e-3}])
def test_compiled_rows_equal_the_plain_python_rows_bit_for_bit(distortion):
    assert RegionGeometry(camera(), compiled=True)._compiled is None  # no distortion: the plain rows
    assert RegionGeometry(camera(**distortion))._compiled is None  # one-off geometries: the plain rows
    geometry = RegionGeometry(camera(**distortion), compiled=True)
    assert geometry._compiled is not None  # built: it agreed on probe boxes
    rng = np.random.default_rng(9)
    n_none = 0
    for n in rng.integers(1, SCALAR_MAX_REGIONS + 1, 300):
        boxes, areas = random_boxes(rng, n)
        got = geometry.rows(boxes.tolist(), areas.tolist())
        assert got == geometry.python_rows(boxes.tolist(), areas.tolist())
        n_none += got.count(None)
    assert n_none > 0  # regions above the horizon met too
