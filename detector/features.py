"""Dimensional features of image regions (paper section 4, eqs. 1-11), vectorised.

For every region of one frame, in one call:

    [estimated width m, estimated height m, estimated contour area m^2,
     distance m, camera tilt deg, camera height m]

Conventions: boxes are OpenCV ``boundingRect`` tuples (x, y, w, h) in pixels of
the *distorted* frame; pixel centres lie on integers, so a box spans the
continuous interval [x - 0.5, x + w - 0.5] x [y - 0.5, y + h - 0.5]. Only the
three pixels each region needs (bottom-left, bottom-right, top-centre) are
undistorted (the paper's "pixels of interest"), all regions of a frame in one
call. Distance is the forward ground distance along the camera heading (eq. 4),
see ``detector.camera``.

``RegionGeometry`` holds a camera's constants of these equations, computed
once; a detector keeps one and calls it every frame. A frame usually holds a
handful of regions, for which numpy's per-call dispatch costs more than the
arithmetic, so ``RegionGeometry.rows`` does the handful in plain Python (same
formulas; results agree with the vectorised path to rounding).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from detector.camera import MIN_DEPRESSION_RAD, CameraModel
from detector.features_compiled import feature_rows
from detector.undistort import compiled_undistortion, lens_constants, opencv_undistortion

FEATURE_NAMES = ("width_m", "height_m", "area_m2", "distance_m", "tilt_deg", "camera_height_m")
N_FEATURES = len(FEATURE_NAMES)

# up to this many regions, scalar Python beats numpy dispatch (measured: ~equal at 24 regions)
SCALAR_MAX_REGIONS = 16


class RegionGeometry:
    """One camera's constants of eqs. 1-11, and the features of regions seen by it.

    Conventions as the module's: boxes (x, y, w, h) px of the distorted frame,
    contour areas px, features in ``FEATURE_NAMES`` order and units.
    """

    def __init__(self, camera: CameraModel, *, compiled: bool = False) -> None:
        self.camera = camera
        self.tilt_deg = camera.tilt_deg
        self.height_m = camera.height_m
        self.tilt_rad = math.radians(camera.tilt_deg)
        # the same numpy scalars the vectorised formulas used before they were hoisted here
        theta = np.radians(camera.tilt_deg)
        self.sin_tilt = float(np.sin(theta))
        self.cos_tilt = float(np.cos(theta))
        self.fx_px, self.fy_px, self.cy_px = camera.fx_px, camera.fy_px, camera.cy_px
        self.distorted = camera.has_distortion
        # ``compiled`` (a detector's, used every frame): OpenCV's values, compiled where they are
        # OpenCV's on every pixel a region can give (``detector.undistort``; a few microseconds
        # less per call, several calls a frame; checking a camera takes ~0.1 s, once per process,
        # so one-off geometries, as training's many cameras, keep OpenCV)
        self._undistort = None
        lens = None
        if self.distorted:
            intrinsic, distortion = camera.intrinsic_matrix, camera.distortion
            size_px = (camera.width_px, camera.height_px)
            if compiled:
                self._undistort = compiled_undistortion(intrinsic, distortion, *size_px)
            if self._undistort is not None:
                lens = lens_constants(intrinsic, distortion, *size_px)
            else:
                self._undistort = opencv_undistortion(intrinsic, distortion)
        # rows' plain Python compiled for a distorted lens (detector.features_compiled), where it
        # gives the same rows; without distortion the plain rows are faster (measured)
        self._compiled = None
        if lens is not None:
            coefs, *scalars, half_grid = lens
            camera_constants = (self.tilt_rad, self.cy_px, self.fy_px, self.height_m, self.sin_tilt,
                                self.cos_tilt, self.fx_px, self.tilt_deg)  # fmt: skip
            self._compiled = (np.array(camera_constants, np.float64), coefs, np.array([*scalars, *half_grid]))
            if not self._compiled_rows_agree(camera.width_px, camera.height_px):
                self._compiled = None

    # ------------------------------------------------------------ undistortion
    def undistort(self, uv_px: np.ndarray) -> np.ndarray:
        """(N, 2) float64 distorted pixels -> (N, 2) ideal pixels; as ``CameraModel.undistort_pixels``."""
        if not self.distorted or len(uv_px) == 0:
            return uv_px
        return self._undistort(uv_px)

    # -------------------------------------------------------------- vectorised
    def features(self, boxes_px: np.ndarray, areas_px: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(features (N, 6), valid (N,) bool)`` of N regions; NaN rows have no ground point."""
        boxes = np.asarray(boxes_px, dtype=np.float64).reshape(-1, 4)
        areas = np.asarray(areas_px, dtype=np.float64).reshape(-1)
        n = len(boxes)
        feats = np.full((n, N_FEATURES), np.nan)
        if n == 0:
            return feats, np.zeros(0, dtype=bool)
        x, y, w, h = boxes.T
        left, right = x - 0.5, x + w - 0.5
        top, bottom = y - 0.5, y + h - 0.5
        pts = np.empty((3 * n, 2))
        pts[:n, 0], pts[n : 2 * n, 0], pts[2 * n :, 0] = left, right, (left + right) / 2
        pts[: 2 * n, 1] = np.concatenate([bottom, bottom])
        pts[2 * n :, 1] = top
        und = self.undistort(pts)
        bl, br, tc = und[:n], und[n : 2 * n], und[2 * n :]
        v_bottom = (bl[:, 1] + br[:, 1]) / 2.0

        b = (v_bottom - self.cy_px) / self.fy_px
        alpha = self.tilt_rad + np.arctan(b)  # eqs. 2-3
        ground = alpha > MIN_DEPRESSION_RAD
        with np.errstate(divide="ignore", invalid="ignore"):
            distance_m = np.where(
                ground, self.height_m / np.tan(np.maximum(alpha, MIN_DEPRESSION_RAD)), np.nan
            )  # eq. 4
            beta = self.tilt_rad + np.arctan((tc[:, 1] - self.cy_px) / self.fy_px)
            height_m = self.height_m - distance_m * np.tan(beta)  # eqs. 5-6
            # eqs. 7-10: camera-frame depth of the bottom row's ground point times the lateral span
            z_cam = np.where(ground, self.height_m / (self.sin_tilt + b * self.cos_tilt), np.nan)
            width_m = z_cam * np.abs(br[:, 0] - bl[:, 0]) / self.fx_px
            area_m2 = areas * height_m * width_m / (w * h)  # eq. 11
        valid = np.isfinite(distance_m)
        feats[:, 0] = width_m
        feats[:, 1] = height_m
        feats[:, 2] = area_m2
        feats[:, 3] = distance_m
        feats[:, 4] = self.tilt_deg
        feats[:, 5] = self.height_m
        feats[~valid] = np.nan
        return feats, valid

    # ------------------------------------------------------------------ scalar
    def rows(
        self, boxes_px: Sequence[Sequence[float]], areas_px: Sequence[float]
    ) -> list[list[float] | None]:
        """Feature rows of N regions as Python lists, None for a region with no ground point.

        Plain Python for up to ``SCALAR_MAX_REGIONS`` regions, the vectorised
        ``features`` beyond; either way one undistortion call for all of them.
        """
        n = len(boxes_px)
        if n > SCALAR_MAX_REGIONS:
            feats, valid = self.features(np.asarray(boxes_px), np.asarray(areas_px))
            return [
                row if ok else None for row, ok in zip(feats.tolist(), valid.tolist(), strict=True)
            ]
        if self._compiled is not None and n:
            feats, valid = np.empty((n, N_FEATURES)), np.empty(n, np.bool_)
            boxes = np.array(boxes_px, np.float64).reshape(n, 4)
            if feature_rows(boxes, np.array(areas_px, np.float64), *self._compiled, feats, valid):
                rows = feats.tolist()
                tilt_deg, cam_h = self.tilt_deg, self.height_m
                for row in rows:  # the camera's own numbers, as the plain rows carry them
                    row[4], row[5] = tilt_deg, cam_h
                return [row if ok else None for row, ok in zip(rows, valid.tolist(), strict=True)]
        return self.python_rows(boxes_px, areas_px)

    def python_rows(
        self, boxes_px: Sequence[Sequence[float]], areas_px: Sequence[float]
    ) -> list[list[float] | None]:
        """``rows`` of up to ``SCALAR_MAX_REGIONS`` regions in plain Python (the reference of the
        compiled rows), one undistortion call for all of them."""
        n = len(boxes_px)
        if self.distorted and n:
            pts = []
            for x, y, w, h in boxes_px:
                left, right = x - 0.5, x + w - 0.5
                pts += ((left, y + h - 0.5), (right, y + h - 0.5), ((left + right) / 2, y - 0.5))
            und = self.undistort(np.array(pts, np.float64)).tolist()
        out: list[list[float] | None] = []
        tilt_rad, cy, fy, cam_h = self.tilt_rad, self.cy_px, self.fy_px, self.height_m
        for k, ((x, y, w, h), area) in enumerate(zip(boxes_px, areas_px, strict=True)):
            if self.distorted:
                (u_left, v_left), (u_right, v_right), (_, v_top) = und[3 * k : 3 * k + 3]
            else:
                u_left, u_right = x - 0.5, x + w - 0.5
                v_left = v_right = y + h - 0.5
                v_top = y - 0.5
            b = ((v_left + v_right) / 2.0 - cy) / fy
            alpha = tilt_rad + math.atan(b)
            if not alpha > MIN_DEPRESSION_RAD:
                out.append(None)
                continue
            # 0 < alpha < pi here (tilt < 90 deg, |atan| < 90 deg): tan(alpha) is never 0
            distance_m = cam_h / math.tan(alpha)
            height_m = cam_h - distance_m * math.tan(tilt_rad + math.atan((v_top - cy) / fy))
            z_cam = cam_h / (self.sin_tilt + b * self.cos_tilt)
            width_m = z_cam * abs(u_right - u_left) / self.fx_px
            area_m2 = area * height_m * width_m / (w * h) if w * h else math.nan
            out.append([width_m, height_m, area_m2, distance_m, self.tilt_deg, cam_h])
        return out

    def _compiled_rows_agree(self, width_px: int, height_px: int) -> bool:
        """Whether the compiled rows equal the plain Python rows bit for bit on probe boxes all
        over the frame (above the horizon too)."""
        rng = np.random.default_rng(0)
        xy = rng.integers(0, (width_px, height_px), (512, 2))
        wh = rng.integers(1, np.maximum((width_px, height_px) - xy, 2), (512, 2))
        boxes = np.column_stack([xy, np.minimum(wh, (width_px, height_px) - xy)]).tolist()
        areas = (rng.uniform(0.2, 1.0, 512) * np.prod(wh, axis=1)).tolist()
        return all(
            self.rows(boxes[i : i + 8], areas[i : i + 8]) == self.python_rows(boxes[i : i + 8], areas[i : i + 8])
            for i in range(0, 512, 8)
        )


def region_features(
    camera: CameraModel, boxes_px: np.ndarray, areas_px: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Features for N regions; returns ``(features (N, 6), valid (N,) bool)``.

    A region is invalid (its feature row is NaN) when its bottom edge lies at or
    above the horizon: it has no ground point, so no distance.
    """
    return RegionGeometry(camera).features(boxes_px, areas_px)


def estimated_height_m(
    camera: CameraModel, distance_m: np.ndarray, v_top_px: np.ndarray
) -> np.ndarray:
    """Height, at forward distance d, of the ray through undistorted row v_top (eqs. 5-6), m.

    The ray through the top row has depression beta; at forward distance d it is
    ``h_c - d * tan(beta)`` above the ground: the same triangle as the paper's
    h_1 * sin(eta) / sin(epsilon), written without the intermediate angles.
    """
    beta = camera.depression_rad(v_top_px)
    return camera.height_m - np.asarray(distance_m) * np.tan(beta)


def estimated_width_m(
    camera: CameraModel, v_bottom_px: np.ndarray, u_left_px: np.ndarray, u_right_px: np.ndarray
) -> np.ndarray:
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
        z_cam = np.where(
            alpha > MIN_DEPRESSION_RAD, camera.height_m / (np.sin(theta) + b * np.cos(theta)), np.nan
        )
    return z_cam * np.abs(np.asarray(u_right_px) - np.asarray(u_left_px)) / camera.fx_px
