"""The compiled undistortion (``detector.undistort``) gives OpenCV's values bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from detector.features import RegionGeometry
from detector.undistort import compiled_undistortion, opencv_undistortion
from tests.detector.cameras import scene_b


@pytest.mark.parametrize(
    "distortion",
    [{"k1": -0.05}, {"k1": -0.08, "k2": 0.01}, {"k1": -0.3, "k2": 0.1, "p1": 1e-3, "p2": -2e-3, "k3": 0.02}],
)
def test_compiled_undistortion_is_opencvs_on_every_pixel_regions_give(distortion):
    cam = scene_b(**distortion)
    compiled = compiled_undistortion(cam.intrinsic_matrix, cam.distortion, cam.width_px, cam.height_px)
    assert compiled is not None  # built: equal on the whole half-pixel grid (checked when built)
    opencv = opencv_undistortion(cam.intrinsic_matrix, cam.distortion)
    rng = np.random.default_rng(2)
    # box corners and centres: half pixels from -0.5 to the frame's size - 0.5
    uv = rng.integers((-1, -1), (2 * cam.width_px, 2 * cam.height_px), (5000, 2)) / 2.0
    assert np.array_equal(compiled(uv), opencv(uv))
    # off that grid (never from a region) OpenCV itself answers
    off = rng.uniform((-30, -30), (cam.width_px + 30, cam.height_px + 30), (500, 2))
    assert np.array_equal(compiled(off), opencv(off))
    assert np.array_equal(RegionGeometry(cam, compiled=True).undistort(uv), cam.undistort_pixels(uv))


def test_a_lens_where_the_compiled_iteration_differs_keeps_opencv():
    cam = scene_b(k1=-0.4, p1=0.05, p2=0.05)  # strong: OpenCV's iteration goes elsewhere on some pixels
    assert compiled_undistortion(cam.intrinsic_matrix, cam.distortion, cam.width_px, cam.height_px) is None
    uv = np.random.default_rng(4).integers((-1, -1), (640, 480), (400, 2)) / 2.0
    assert np.array_equal(RegionGeometry(cam, compiled=True).undistort(uv), cam.undistort_pixels(uv))
