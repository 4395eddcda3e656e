"""Dimensional features of image regions (paper section 4, eqs. 1-11), vectorised.

For every region of one frame, in one call:

    [estimated width m, estimated height m, estimated contour area m^2,
     distance m, camera tilt deg, camera height m]

Conventions: boxes are OpenCV ``boundingRect`` tuples (x, y, w, h) in pixels of
the *distorted* frame; pixel centres lie on integers, so a box spans the
continuous interval [x - 0.5, x + w - 0.5] x [y - 0.5, y + h - 0.5]. Only the
three pixels each region needs (bottom-left, bottom-right, top-centre) are
undistorted (the paper's "pixels of interest"). Distance is the forward ground
distance along the camera heading (eq. 4), see ``detector.camera``.
"""

from __future__ import annotations

import numpy as np

from detector.camera import CameraModel

FEATURE_NAMES = ("width_m", "height_m", "area_m2", "distance_m", "tilt_deg", "camera_height_m")
N_FEATURES = len(FEATURE_NAMES)


def region_features(camera: CameraModel, boxes_px: np.ndarray, areas_px: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Features for N regions; returns ``(features (N, 6), valid (N,) bool)``.

    A region is invalid (its feature row is NaN) when its bottom edge lies at or
    above the horizon: it has no ground point, so no distance.
    """
    boxes = np.asarray(boxes_px, dtype=np.float64).reshape(-1, 4)
    areas = np.asarray(areas_px, dtype=np.float64).reshape(-1)
    n = len(boxes)
    feats = np.full((n, N_FEATURES), np.nan)
    if n == 0:
        return feats, np.zeros(0, dtype=bool)
    x, y, w, h = boxes.T
    left, right = x - 0.5, x + w - 0.5
    top, bottom = y - 0.5, y + h - 0.5
    pts = np.concatenate(
        [np.column_stack([left, bottom]), np.column_stack([right, bottom]), np.column_stack([(left + right) / 2, top])]
    )
    und = camera.undistort_pixels(pts)
    bl, br, tc = und[:n], und[n : 2 * n], und[2 * n :]
    v_bottom = (bl[:, 1] + br[:, 1]) / 2.0

    distance_m = camera.forward_distance_m(v_bottom)  # eqs. 2-4
    valid = np.isfinite(distance_m)
    height_m = estimated_height_m(camera, distance_m, tc[:, 1])  # eqs. 5-6
    width_m = estimated_width_m(camera, v_bottom, bl[:, 0], br[:, 0])  # eqs. 7-10
    with np.errstate(divide="ignore", invalid="ignore"):
        area_m2 = areas * height_m * width_m / (w * h)  # eq. 11

    feats[:, 0] = width_m
    feats[:, 1] = height_m
    feats[:, 2] = area_m2
    feats[:, 3] = distance_m
    feats[:, 4] = camera.tilt_deg
    feats[:, 5] = camera.height_m
    feats[~valid] = np.nan
    return feats, valid


def estimated_height_m(camera: CameraModel, distance_m: np.ndarray, v_top_px: np.ndarray) -> np.ndarray:
    """Height, at forward distance d, of the ray through undistorted row v_top (eqs. 5-6), m.

    The ray through the top row has depression beta; at forward distance d it is
    ``h_c - d * tan(beta)`` above the ground: the same triangle as the paper's
    h_1 * sin(eta) / sin(epsilon), written without the intermediate angles.
    """
    beta = camera.depression_rad(v_top_px)
    return camera.height_m - np.asarray(distance_m) * np.tan(beta)


def estimated_width_m(camera: CameraModel, v_bottom_px: np.ndarray, u_left_px: np.ndarray, u_right_px: np.ndarray) -> np.ndarray:
    """Lateral distance between the back-projected bottom corners (eqs. 7-10), m.

    For row v the camera-frame depth of its ground point is z_cam (eq. 9); the
    lateral camera coordinate of pixel u is ``z_cam * (u - c_x) / f_x`` (eq. 8),
    so the width is ``z_cam * |u_r - u_l| / f_x``.
    """
    alpha = camera.depression_rad(v_bottom_px)
    theta = np.radians(camera.tilt_deg)
    with np.errstate(divide="ignore", invalid="ignore"):
        # ray direction in camera frame (a, b, 1); its depth per unit slant is
        # z_cam = h_c / (sin(theta) + b cos(theta)) with b = (v - c_y) / f_y
        b = (np.asarray(v_bottom_px) - camera.cy_px) / camera.fy_px
        z_cam = np.where(alpha > 1e-9, camera.height_m / (np.sin(theta) + b * np.cos(theta)), np.nan)
    return z_cam * np.abs(np.asarray(u_right_px) - np.asarray(u_left_px)) / camera.fx_px
