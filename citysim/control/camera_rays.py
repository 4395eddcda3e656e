"""A camera's pixel <-> world maths for one point or a few, without the per-call overhead.

``DetectorLocated`` places each confirmed detection without a ground position (fast mode's drawn
ones) with ``CameraModel.pixel_to_ground`` of its box's bottom centre, and fast mode boxes each
candidate with ``CameraModel.project``: ~20k calls of each an hour at 22:00, each mostly numpy's
and pydantic's per-call cost (array checks, intrinsics recomputed from the focal length). Here the
camera's values are read once and the same operations are done on the same numbers, in the same
shapes where a matrix product or OpenCV is involved (their results are then the same bit for bit)
and on plain floats where numpy did one IEEE operation per element (the same result by IEEE).
Ground points are also kept per pixel: boxes are whole pixels, so the same bottom centres come
back again and again (road users keep their lanes).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

#: Pixels remembered per camera before the memo starts over (bounds its memory).
MAX_PIXELS = 50_000
#: ``CameraModel.undistort_pixels``' criterion (iterative, tight)
_UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-10)
_NO_ROTATION = np.zeros(3)


class CameraRays:
    """``pixel_to_ground`` of one pixel (remembered) and ``project`` of points, for ``camera``
    (a ``detector.camera.CameraModel``), as those methods compute them.

    Conventions (``CameraModel``'s): pixels are OpenCV's (u right, v down, pixel centres on
    integers, the distorted image); world points are metres, x along the street, y across it,
    z up from the ground (z = 0); the camera frame is OpenCV's (x right, y down, z forward)."""

    def __init__(self, camera):
        self.camera = camera
        self.fx_px, self.fy_px, self.cx_px, self.cy_px = camera.fx_px, camera.fy_px, camera.cx_px, camera.cy_px
        self.intrinsic = camera.intrinsic_matrix
        self.distortion = camera.distortion
        self.has_distortion = camera.has_distortion
        self.rotation = camera.rotation_world_to_cam
        self.rotation_t = self.rotation.T  # the view world_to_cam multiplies by (the same strides: the same product)
        self.position_m = camera.position_m
        self.px_m, self.py_m = (float(v) for v in camera.position_m[:2])
        self.height_m = camera.height_m
        self._eye = np.eye(3)
        self._ground: dict[tuple[float, float], tuple[float, float] | None] = {}

    def ground_xy_m(self, u_px: float, v_px: float) -> tuple[float, float] | None:
        """World (x, y) of the ground point seen at pixel (u, v), m (``pixel_to_ground``); None:
        none there (above the horizon, or not finite)."""
        key = (u_px, v_px)
        if key in self._ground:
            return self._ground[key]
        if len(self._ground) >= MAX_PIXELS:
            self._ground.clear()
        xy = self._ground[key] = self._ground_xy_m(u_px, v_px)
        return xy

    def _ground_xy_m(self, u_px: float, v_px: float) -> tuple[float, float] | None:
        if self.has_distortion:  # the (1, 1, 2) array undistort_pixels reshapes its (1, 2) one to
            uv = cv2.undistortPointsIter(np.array([[[u_px, v_px]]], dtype=np.float64), self.intrinsic,
                                         self.distortion, self._eye, self.intrinsic, _UNDISTORT_CRITERIA)  # fmt: skip
            u, v = uv.ravel().tolist()
        else:
            u, v = float(u_px), float(v_px)
        rays_cam = np.array([[(u - self.cx_px) / self.fx_px, (v - self.cy_px) / self.fy_px, 1.0]])
        dx, dy, dz = (rays_cam @ self.rotation)[0].tolist()  # the (1, 3) @ (3, 3) product pixel_to_ground makes
        if not dz < -1e-12:
            return None
        s = -self.height_m / dz
        x_m, y_m = self.px_m + dx * s, self.py_m + dy * s
        return (x_m, y_m) if math.isfinite(x_m) and math.isfinite(y_m) else None

    def project_px(self, points_m: np.ndarray) -> list[list[float]]:
        """``project`` (distorted) of (N, 3) world points, as lists [u, v] (NaN: behind the camera)."""
        cam = (points_m - self.position_m) @ self.rotation_t  # world_to_cam's product, the same shapes
        # all in front (most boxes): every point, as they are; the depths compared as plain floats,
        # the comparison numpy's ``cam[:, 2] > 0.01`` makes (a tenth of the cost on a box's points)
        if self.has_distortion and all(z > 0.01 for z in cam[:, 2].tolist()):
            px, _ = cv2.projectPoints(cam, _NO_ROTATION, _NO_ROTATION, self.intrinsic, self.distortion)
            return px.reshape(-1, 2).tolist()
        front = cam[:, 2] > 0.01
        out = np.full((len(cam), 2), np.nan)
        if not front.any():
            return out.tolist()
        if self.has_distortion:
            px, _ = cv2.projectPoints(cam[front], _NO_ROTATION, _NO_ROTATION, self.intrinsic, self.distortion)
            out[front] = px.reshape(-1, 2)
        else:
            z = cam[front, 2]
            out[front, 0] = self.fx_px * cam[front, 0] / z + self.cx_px
            out[front, 1] = self.fy_px * cam[front, 1] / z + self.cy_px
        return out.tolist()
