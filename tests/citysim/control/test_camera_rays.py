"""``CameraRays`` computes what ``CameraModel.pixel_to_ground`` and ``project`` compute, bit for bit."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from citysim.config.scenario import load_scenario
from citysim.control.camera_rays import CameraRays
from citysim.sim.night import build_night

SCENARIO = Path(__file__).resolve().parents[3] / "scenarios" / "suburban_night.yaml"


@pytest.fixture(scope="module")
def cameras():
    street = build_night(load_scenario(SCENARIO)).street
    return [site.camera for site in street.cameras]


def test_ground_points_are_pixel_to_ground_s(cameras):
    rng = np.random.default_rng(3)
    for cam in cameras[:6]:
        rays = CameraRays(cam)
        # whole and half pixels over the frame and beyond it (above the horizon: no ground point)
        uv = np.column_stack([rng.integers(-50, cam.width_px + 50, 400) + rng.choice([0.0, 0.5, -0.5], 400),
                              rng.integers(-50, cam.height_px + 50, 400) - 0.5])  # fmt: skip
        for u, v in uv.tolist():
            ground = cam.pixel_to_ground(np.array([[u, v]], dtype=np.float64))[0]
            expected = (float(ground[0]), float(ground[1])) if np.all(np.isfinite(ground)) else None
            assert rays.ground_xy_m(u, v) == expected
            assert rays.ground_xy_m(u, v) == expected  # and the remembered one
    assert any(CameraRays(cam).ground_xy_m(cam.width_px / 2, 0.0) is None for cam in cameras)


def test_projected_points_are_project_s(cameras):
    rng = np.random.default_rng(4)
    for cam in cameras[:6]:
        rays = CameraRays(cam)
        for n in (1, 2, 3, 6, 10):
            # around the pole, behind the camera too (NaN)
            pts = np.column_stack([cam.x_m + rng.uniform(-40, 40, n), rng.uniform(-8, 8, n), rng.uniform(0, 2, n)])
            got, expected = rays.project_px(pts), cam.project(pts).tolist()
            assert [[u if not math.isnan(u) else "nan" for u in row] for row in got] == \
                [[u if not math.isnan(u) else "nan" for u in row] for row in expected]  # fmt: skip
