"""``RegionGeometry.rows``' plain Python compiled (numba) for a distorted lens: one call.

Operation for operation the plain loop (the same float64 arithmetic, ``math.atan``/``math.tan``
from the same C library; no fast-math), with ``detector.undistort``'s compiled undistortion
inside. ``RegionGeometry`` uses it only where it gives the plain Python rows bit for bit on probe
boxes.

Design: docs/design/modules.md (Compiled region rows)
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from detector.camera import MIN_DEPRESSION_RAD
from detector.undistort import _undistort


@njit(cache=True, nogil=True)
def feature_rows(boxes, areas, camera, coefs, lens, out, valid):  # pragma: no cover - compiled
    """Rows (N, 6) into ``out`` and ground-point flags into ``valid`` of boxes (N, 4) float64
    (x, y, w, h px) and areas (N,) seen through a distorted lens; ``camera``: (tilt rad, c_y, f_y,
    height m, sin tilt, cos tilt, f_x, tilt deg); ``coefs`` (14,) and ``lens`` (f_x, f_y, c_x, c_y,
    2 x max u, 2 x max v): ``detector.undistort``'s. Arrays, not tuples: numba types a tuple
    argument element by element at every call. False if a pixel fell off the undistortion's
    checked grid (``out`` is then unfinished)."""
    tilt_rad, cy, fy, cam_h = camera[0], camera[1], camera[2], camera[3]
    sin_tilt, cos_tilt, fx, tilt_deg = camera[4], camera[5], camera[6], camera[7]
    n = boxes.shape[0]
    und = np.empty((3 * n, 2))
    pts = np.empty((3 * n, 2))
    for k in range(n):
        x, y, w, h = boxes[k, 0], boxes[k, 1], boxes[k, 2], boxes[k, 3]
        left, right = x - 0.5, x + w - 0.5
        pts[3 * k, 0], pts[3 * k, 1] = left, y + h - 0.5
        pts[3 * k + 1, 0], pts[3 * k + 1, 1] = right, y + h - 0.5
        pts[3 * k + 2, 0], pts[3 * k + 2, 1] = (left + right) / 2, y - 0.5
    if not _undistort(pts, coefs, lens[0], lens[1], lens[2], lens[3], lens[4:], und):
        return False
    for k in range(n):
        w, h = boxes[k, 2], boxes[k, 3]
        u_left, v_left = und[3 * k, 0], und[3 * k, 1]
        u_right, v_right = und[3 * k + 1, 0], und[3 * k + 1, 1]
        v_top = und[3 * k + 2, 1]
        b = ((v_left + v_right) / 2.0 - cy) / fy
        alpha = tilt_rad + math.atan(b)
        valid[k] = alpha > MIN_DEPRESSION_RAD
        if not valid[k]:
            continue
        distance_m = cam_h / math.tan(alpha)
        height_m = cam_h - distance_m * math.tan(tilt_rad + math.atan((v_top - cy) / fy))
        z_cam = cam_h / (sin_tilt + b * cos_tilt)
        width_m = z_cam * abs(u_right - u_left) / fx
        area_m2 = areas[k] * height_m * width_m / (w * h) if w * h else math.nan
        out[k, 0], out[k, 1], out[k, 2] = width_m, height_m, area_m2
        out[k, 3], out[k, 4], out[k, 5] = distance_m, tilt_deg, cam_h
    return True
