"""Where a training sample stands in a camera's view, and the region the segmenter would make of it.

``ground_points`` draws ground points a camera sees; ``shape_region`` projects a
3D model (``detector.train.shapes``) there, sweeps it over the exposure for
motion blur, cleans it with the segmenter's morphology and measures the box and
contour area the detector would measure; ``jitter`` moves the box edges by a
pixel or so, as a real segmentation does. Cameras stand at the origin looking
along +x, so a ground point's forward distance is its world x, metres.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from detector.camera import CameraModel
from detector.train.config import TrainingConfig
from detector.train.shape_parts import Shape
from detector.train.silhouette import rasterise_parts


def _forward_range_m(cam: CameraModel, config: TrainingConfig) -> tuple[float, float]:
    """Forward distances (m) of ground points the camera sees, clipped to the config's range."""
    half_fov = math.atan(cam.sensor_h_mm / (2 * cam.focal_mm))
    tilt = math.radians(cam.tilt_deg)
    near = cam.height_m / math.tan(tilt + half_fov) if tilt + half_fov < math.pi / 2 else 0.0
    far = cam.height_m / math.tan(tilt - half_fov) if tilt - half_fov > 1e-6 else math.inf
    return max(near, config.min_distance_m), min(far, config.max_distance_m)


def ground_points(
    rng: np.random.Generator, cam: CameraModel, n: int, config: TrainingConfig
) -> np.ndarray:
    """n ground points (n, 2) in view: forward distance uniform, column uniform; NaN if none."""
    near, far = _forward_range_m(cam, config)
    if far <= near:
        return np.full((n, 2), np.nan)
    d = rng.uniform(near, far, size=n)
    u = rng.uniform(0, cam.width_px, size=n)
    v = cam.cy_px + cam.fy_px * np.tan(np.arctan(cam.height_m / d) - math.radians(cam.tilt_deg))
    return cam.pixel_to_ground(np.column_stack([u, v]), undistorted=True)[:, :2]


def shape_region(
    cam: CameraModel,
    shape: Shape,
    velocity_mps: np.ndarray,
    exposure_s: float,
    config: TrainingConfig,
    kernel: np.ndarray,
) -> tuple[np.ndarray, float] | None:
    """Box (x, y, w, h) px and contour area px of the model as the segmenter would see it.

    The model is swept over the exposure (each part becomes the convex hull of
    its start and end positions), opened and dilated like the segmenter's mask,
    and its external contours are measured. None when the region is lost
    (out of view, touching the border, too small or too sparse).
    """
    start = shape.corners_m
    swept = np.concatenate([start, start + velocity_mps * exposure_s], axis=1)
    p, k, _ = swept.shape
    uv = cam.project(swept.reshape(-1, 3), distort=True).reshape(p, k, 2)
    # cheap early exits before rasterising: a vertex behind the camera or beyond a
    # border pixel centre means the region would be cut; a tiny box cannot hold
    # the minimum area
    lo, hi = uv.reshape(-1, 2).min(axis=0), uv.reshape(-1, 2).max(axis=0)
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        return None
    if lo[0] < 0 or lo[1] < 0 or hi[0] > cam.width_px - 1 or hi[1] > cam.height_px - 1:
        return None
    if (hi[0] - lo[0] + 3) * (
        hi[1] - lo[1] + 3
    ) < config.min_area_fraction * cam.width_px * cam.height_px:
        return None
    margin = config.open_kernel_px * (config.dilate_iterations + 1)
    sil = rasterise_parts(uv, cam.width_px, cam.height_px, margin_px=margin)
    if sil is None or sil.touches_border:
        return None
    mask = cv2.morphologyEx(sil.mask, cv2.MORPH_OPEN, kernel)
    if config.dilate_iterations > 0:
        mask = cv2.dilate(mask, kernel, iterations=config.dilate_iterations)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    if not contours:
        return None
    # the whole model is one training region, even when the segmenter would split it
    x, y, w, h = cv2.boundingRect(np.concatenate(contours))
    area = float(sum(cv2.contourArea(c) for c in contours))
    x, y = x + sil.offset_px[0], y + sil.offset_px[1]
    if x <= 0 or y <= 0 or x + w >= cam.width_px or y + h >= cam.height_px:
        return None
    if (
        area < config.min_area_fraction * cam.width_px * cam.height_px
        or area < config.min_extent * w * h
    ):
        return None
    return np.array([x, y, w, h], dtype=np.float64), area


def jitter(
    rng: np.random.Generator, box: np.ndarray, area: float, jitter_px: int
) -> tuple[np.ndarray, float]:
    """Move each box edge by up to jitter_px; the contour area scales with the box."""
    if jitter_px <= 0:
        return box, area
    dl, dt, dr, db = rng.integers(-jitter_px, jitter_px + 1, size=4)
    x, y, w, h = box
    nw, nh = max(w - dl + dr, 1.0), max(h - dt + db, 1.0)
    return np.array([x + dl, y + dt, nw, nh]), area * (nw * nh) / (w * h)
