"""OpenCV's iterative undistortion of pixels, compiled (numba), for the pixels regions give.

Why: ``cv2.undistortPointsIter`` costs microseconds of argument conversion per call, and the
detector calls it several times a frame for a handful of points (the features' corners, the
tracks' ground points, division's parts), after MOG2 has walked the caches. This is
OpenCV's ``cvUndistortPointsInternal`` for a camera matrix ``K``, distortion (k1, k2, p1, p2
[, k3 ...]), no rectification and ``P = K`` under the detector's criterion (40 iterations or a
reprojection error below 1e-10 px): the same float64 operations in the same order, compiled
without fast-math (no reassociation, no fused multiply-add); the identity tilt and
rectification matrices, whose products are exact, are left out.

Exactness is checked, not assumed: ``compiled_undistortion`` compares it with OpenCV on every
point a region of the frame can give (box corners and centres lie on the half-pixel grid from
-0.5 to the frame's size - 0.5) and returns None if any value differs (strong distortion sends
OpenCV's iteration where this one goes elsewhere); points off that grid are left to OpenCV.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import cv2
import numpy as np
from numba import njit

#: CameraModel.undistort_pixels's criterion: at most 40 iterations, or a reprojection error < 1e-10 px
CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-10)
# cameras already checked, by (K, distortion, frame size): the check takes ~0.1 s
_CHECKED: dict[tuple, bool] = {}


@njit(cache=True, nogil=True)
def _undistort(uv, k, fx, fy, cx, cy, half_grid, out):  # pragma: no cover - compiled
    """``out`` (N, 2) the undistorted ``uv`` (N, 2); False (out unfinished) if a point is off the
    half-pixel grid ``half_grid`` = (2 x max u, 2 x max v), where exactness was not checked."""
    ifx = 1.0 / fx
    ify = 1.0 / fy
    k0, k1, k2, k3, k4 = k[0], k[1], k[2], k[3], k[4]
    k5, k6, k7, k8, k9, k10, k11 = k[5], k[6], k[7], k[8], k[9], k[10], k[11]
    max_error = np.finfo(np.float64).max
    for i in range(uv.shape[0]):
        u = uv[i, 0]
        v = uv[i, 1]
        if not (-1.0 <= 2.0 * u <= half_grid[0] and -1.0 <= 2.0 * v <= half_grid[1]):
            return False
        if 2.0 * u != math.floor(2.0 * u) or 2.0 * v != math.floor(2.0 * v):
            return False
        x = (u - cx) * ifx
        y = (v - cy) * ify
        x0, y0 = x, y
        error = max_error
        for _ in range(40):
            if error < 1e-10:
                break
            r2 = x * x + y * y
            icdist = (1 + ((k7 * r2 + k6) * r2 + k5) * r2) / (1 + ((k4 * r2 + k1) * r2 + k0) * r2)
            if icdist < 0:
                x = (u - cx) * ifx
                y = (v - cy) * ify
                break
            delta_x = 2 * k2 * x * y + k3 * (r2 + 2 * x * x) + k8 * r2 + k9 * r2 * r2
            delta_y = k2 * (r2 + 2 * y * y) + 2 * k3 * x * y + k10 * r2 + k11 * r2 * r2
            x = (x0 - delta_x) * icdist
            y = (y0 - delta_y) * icdist
            r2 = x * x + y * y
            r4 = r2 * r2
            r6 = r4 * r2
            a1 = 2 * x * y
            a2 = r2 + 2 * x * x
            a3 = r2 + 2 * y * y
            cdist = 1 + k0 * r2 + k1 * r4 + k4 * r6
            icdist2 = 1.0 / (1 + k5 * r2 + k6 * r4 + k7 * r6)
            x_proj = (x * cdist * icdist2 + k2 * a1 + k3 * a2 + k8 * r2 + k9 * r4) * fx + cx
            y_proj = (y * cdist * icdist2 + k2 * a3 + k3 * a1 + k10 * r2 + k11 * r4) * fy + cy
            error = math.sqrt((x_proj - u) * (x_proj - u) + (y_proj - v) * (y_proj - v))
        out[i, 0] = fx * x + 0.0 * y + cx
        out[i, 1] = 0.0 * x + fy * y + cy
    return True


def opencv_undistortion(intrinsic: np.ndarray, distortion: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """``cv2.undistortPointsIter`` of (N, 2) float64 pixels under ``CRITERIA``, no rectification."""
    identity = np.eye(3)  # made once

    def undistort(uv_px: np.ndarray) -> np.ndarray:
        und = cv2.undistortPointsIter(uv_px.reshape(-1, 1, 2), intrinsic, distortion, identity, intrinsic, CRITERIA)
        return und.reshape(-1, 2)

    return undistort


def lens_constants(intrinsic: np.ndarray, distortion: np.ndarray, width_px: int, height_px: int) -> tuple:
    """``_undistort``'s lens arguments: (k (14,), f_x, f_y, c_x, c_y, half-pixel grid (2,))."""
    k = np.zeros(14)
    k[: len(distortion)] = distortion
    fx, fy, cx, cy = (float(intrinsic[i, j]) for i, j in ((0, 0), (1, 1), (0, 2), (1, 2)))
    return k, fx, fy, cx, cy, np.array([2.0 * width_px - 1.0, 2.0 * height_px - 1.0])


def compiled_undistortion(
    intrinsic: np.ndarray, distortion: np.ndarray, width_px: int, height_px: int
) -> Callable[[np.ndarray], np.ndarray] | None:
    """The compiled undistortion of (N, 2) float64 pixels of a ``width_px`` x ``height_px`` frame,
    or None if it differs from OpenCV's anywhere on the frame's half-pixel grid (off the grid the
    function returned calls OpenCV)."""
    k, fx, fy, cx, cy, half_grid = lens_constants(intrinsic, distortion, width_px, height_px)
    opencv = opencv_undistortion(intrinsic, distortion)

    def undistort(uv_px: np.ndarray) -> np.ndarray:
        out = np.empty((len(uv_px), 2))
        return out if _undistort(uv_px, k, fx, fy, cx, cy, half_grid, out) else opencv(uv_px)

    key = (intrinsic.tobytes(), k.tobytes(), width_px, height_px)
    if key not in _CHECKED:
        half_u, half_v = np.meshgrid(np.arange(-1.0, half_grid[0] + 1.0), np.arange(-1.0, half_grid[1] + 1.0))
        grid = np.column_stack([half_u.ravel(), half_v.ravel()]) / 2.0
        _CHECKED[key] = bool(np.array_equal(undistort(grid), opencv(grid)))
    return undistort if _CHECKED[key] else None
