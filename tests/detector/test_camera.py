"""Geometry of CameraModel: round trips against OpenCV's own projection, paper eqs. 1-10."""

import math

import cv2
import numpy as np
import pytest

from detector.camera import CameraError, CameraModel, NoGroundPointError
from detector.features import region_features

# The paper's Table 2 intrinsics: (focal_mm, sensor_w_mm, sensor_h_mm, width_px, height_px)
TABLE2_INTRINSICS = [
    (3.67, 4.8, 3.6, 424, 240),
    (0.73, 0.7, 0.52, 320, 240),
    (3.6, 3.45, 1.94, 424, 240),
]


def random_camera(rng: np.random.Generator, distortion: bool = True) -> CameraModel:
    f, sw, sh, w, h = TABLE2_INTRINSICS[rng.integers(len(TABLE2_INTRINSICS))]
    k = dict(k1=rng.uniform(-0.25, 0.1), k2=rng.uniform(-0.05, 0.05), p1=rng.uniform(-2e-3, 2e-3),
             p2=rng.uniform(-2e-3, 2e-3), k3=0.0) if distortion else {}
    return CameraModel(height_m=rng.uniform(2, 10), tilt_deg=rng.uniform(0, 80), focal_mm=f, sensor_w_mm=sw,
                       sensor_h_mm=sh, width_px=w, height_px=h, x_m=rng.uniform(-50, 50),
                       y_m=rng.uniform(-10, 10), yaw_deg=rng.uniform(-180, 180), **k)


def ground_points_in_view(cam: CameraModel, rng: np.random.Generator, n: int, max_forward_m: float = 50.0):
    """Random ground points whose projection lands inside the central 80% of the frame, within max_forward_m."""
    u = rng.uniform(0.1, 0.9, 4 * n) * cam.width_px
    v = rng.uniform(0.1, 0.9, 4 * n) * cam.height_px
    g = cam.pixel_to_ground(np.column_stack([u, v]), undistorted=True)
    fwd = cam.forward_and_lateral_m(g[:, :2])[:, 0] if len(g) else np.zeros(0)
    keep = np.isfinite(g[:, 0]) & (fwd < max_forward_m)
    return g[keep][:n]


@pytest.mark.parametrize("seed", range(40))
def test_world_pixel_world_round_trip_against_cv2_projectpoints(seed):
    rng = np.random.default_rng(seed)
    cam = random_camera(rng)
    pts = ground_points_in_view(cam, rng, 50)
    assert len(pts) > 10
    px_cv, _ = cv2.projectPoints(pts, cam.rvec, cam.tvec, cam.intrinsic_matrix, cam.distortion)
    px_cv = px_cv.reshape(-1, 2)
    np.testing.assert_allclose(cam.project(pts), px_cv, atol=1e-6)
    back = cam.pixel_to_ground(px_cv)
    err_m = np.linalg.norm(back - pts, axis=1)
    assert err_m.max() < 0.01, f"round trip error {err_m.max():.4f} m"


@pytest.mark.parametrize("seed", range(20))
def test_estimated_height_of_vertical_pole_within_2_percent(seed):
    rng = np.random.default_rng(100 + seed)
    cam = random_camera(rng, distortion=False)
    for foot in ground_points_in_view(cam, rng, 10, max_forward_m=40):
        pole_m = rng.uniform(0.8, 2.0)
        top, bottom = cam.project(np.array([[*foot[:2], pole_m], foot]))
        if not (np.all(np.isfinite(top)) and 0 <= top[1] < cam.height_px):
            continue
        # a pixel-exact "box" of the pole: continuous edges -> x, y, w, h with half-pixel convention
        box = np.array([[bottom[0] + 0.5, top[1] + 0.5, 1.0, bottom[1] - top[1]]])
        feats, valid = region_features(cam, box, np.array([1.0]))
        assert valid[0]
        assert feats[0, 1] == pytest.approx(pole_m, rel=0.02)


@pytest.mark.parametrize("seed", range(20))
def test_estimated_width_of_flat_bar_across_view_within_2_percent(seed):
    rng = np.random.default_rng(200 + seed)
    cam = random_camera(rng, distortion=False)
    left = np.array([-cam.heading_unit[1], cam.heading_unit[0]])
    for centre in ground_points_in_view(cam, rng, 10, max_forward_m=40):
        bar_m = rng.uniform(0.3, 3.0)
        a = np.r_[centre[:2] + left * bar_m / 2, 0.0]
        b = np.r_[centre[:2] - left * bar_m / 2, 0.0]
        pa, pb = cam.project(np.array([a, b]))
        if not (np.all(np.isfinite([pa, pb])) and 0 <= min(pa[0], pb[0]) and max(pa[0], pb[0]) < cam.width_px):
            continue
        assert pa[1] == pytest.approx(pb[1], abs=1e-6)  # same forward distance -> same row
        x0 = min(pa[0], pb[0])
        box = np.array([[x0 + 0.5, pa[1] - 0.5, abs(pb[0] - pa[0]), 1.0]])
        feats, valid = region_features(cam, box, np.array([1.0]))
        assert valid[0]
        assert feats[0, 0] == pytest.approx(bar_m, rel=0.02)


def test_distance_is_paper_eq4_forward_distance():
    cam = CameraModel(height_m=3.1, tilt_deg=22, focal_mm=0.73, sensor_w_mm=0.7, sensor_h_mm=0.52,
                      width_px=320, height_px=240)
    v = np.array([150.0, 200.0, 239.0])
    alpha = math.radians(22) + np.arctan(0.52 / 0.73 * (v / 240 - 0.5))  # eqs. 2-3 with depression angles
    np.testing.assert_allclose(cam.forward_distance_m(v), 3.1 / np.tan(alpha))


def test_rows_above_horizon_have_no_ground_point():
    cam = CameraModel(height_m=5, tilt_deg=5, focal_mm=3.6, sensor_w_mm=3.45, sensor_h_mm=1.94,
                      width_px=424, height_px=240)
    horizon = cam.horizon_row_px
    assert 0 < horizon < cam.height_px
    rows = np.array([0.0, horizon - 1, horizon, horizon + 1e-12])
    d = cam.forward_distance_m(rows)
    assert np.all(np.isnan(d)), d  # never negative, never infinite
    assert np.isnan(cam.pixel_to_ground(np.array([[10.0, horizon - 5]]))).all()
    with pytest.raises(NoGroundPointError, match="above the horizon"):
        cam.ground_point(10.0, horizon - 5)
    below = cam.forward_distance_m(np.array([horizon + 1, cam.height_px - 1]))
    assert np.all(np.isfinite(below)) and np.all(below > 0)
    feats, valid = region_features(cam, np.array([[10, 2, 20, 10], [10, 200, 20, 30]]), np.array([100.0, 300.0]))
    assert valid.tolist() == [False, True]
    assert np.isnan(feats[0]).all()


def test_camera_that_cannot_see_the_ground_is_rejected_with_the_field():
    with pytest.raises(CameraError, match="tilt_deg"):
        CameraModel.from_mapping(dict(height_m=3, tilt_deg=-29, focal_mm=3.67, sensor_w_mm=4.8, sensor_h_mm=3.6,
                                      width_px=424, height_px=240), source="cam.yaml")


def test_camera_file_errors_name_the_file_and_field(tmp_path):
    with pytest.raises(CameraError, match="not found"):
        CameraModel.from_yaml(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("height_m: -1\ntilt_deg: 10\nfocal_mm: 3\nsensor_w_mm: 4\nsensor_h_mm: 3\nwidth_px: 320\nheight_px: 240\n")
    with pytest.raises(CameraError, match=r"bad.yaml: height_m: .*greater than 0"):
        CameraModel.from_yaml(bad)
    typo = tmp_path / "typo.yaml"
    typo.write_text("height_m: 3\ntilt: 10\nfocal_mm: 3\nsensor_w_mm: 4\nsensor_h_mm: 3\nwidth_px: 320\nheight_px: 240\n")
    with pytest.raises(CameraError, match="tilt: unknown field") as exc:
        CameraModel.from_yaml(typo)
    assert "tilt_deg: Field required" in str(exc.value)


def test_undistort_inverts_distortion():
    rng = np.random.default_rng(7)
    cam = random_camera(rng)
    ideal = np.column_stack([rng.uniform(20, cam.width_px - 20, 200), rng.uniform(20, cam.height_px - 20, 200)])
    g = cam.pixel_to_ground(ideal, undistorted=True)
    ok = np.isfinite(g[:, 0])
    distorted = cam.project(g[ok])
    np.testing.assert_allclose(cam.undistort_pixels(distorted), ideal[ok], atol=1e-4)
