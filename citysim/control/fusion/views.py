"""What each camera can see on the ground, in street coordinates: for negative information,
births next to blind stretches, and ``oracle_seen``'s perfect detector.

A camera sees a ground point when it lies ahead of the pole between the ground distance of the
frame's bottom row (``near_m``) and the detector's range (``DETECTION_RANGE_M``), within the
horizontal field of view. Conventions: ground x, y and street s, d in metres
(``citysim.control.fusion.street_frame``); *forward* is the ground distance along the camera's
heading, *lateral* to its left.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import ndtr

from citysim.control.camera_rays import CameraRays
from citysim.control.fusion.street_frame import StreetFrame

#: The detector judges nothing beyond this ground distance, m (its general model's view range).
DETECTION_RANGE_M = 25.0
#: A road user this close to a view's near or far edge is half out of the frame and rarely
#: detected: a miss there says little (``visibility`` counts the view this much smaller), m.
EDGE_M = 2.0


class CameraViews:
    """Every camera's view as arrays (one numpy pass tests points against all cameras).

    Parameters
    ----------
    cameras : sequence of ``detector.camera.CameraModel``
        The street's cameras in camera-index order (``Street.cameras``).
    frame : StreetFrame
        The street's ground <-> street conversion.
    range_m : float
        The far edge of every view, m (default ``DETECTION_RANGE_M``).
    """

    def __init__(self, cameras, frame: StreetFrame, range_m: float = DETECTION_RANGE_M):
        self.frame = frame
        self.pole_xy_m = np.array([[float(c.position_m[0]), float(c.position_m[1])] for c in cameras])
        self.heading = np.array([[float(c.heading_unit[0]), float(c.heading_unit[1])] for c in cameras])
        self.tan_half_fov = np.array([math.tan(math.radians(c.horizontal_fov_deg) / 2.0) for c in cameras])
        self.near_m = np.array([_near_m(c) for c in cameras])
        self.far_m = np.full(len(cameras), float(range_m))
        # the same as plain floats, read per track per judged frame
        self._poles, self._headings = self.pole_xy_m.tolist(), self.heading.tolist()
        self._near, self._far, self._tan = self.near_m.tolist(), self.far_m.tolist(), self.tan_half_fov.tolist()

    @property
    def n(self) -> int:
        return len(self.pole_xy_m)

    def forward_lateral_m(self, xy_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(N, C) forward and lateral ground distances (m) of ground points ``xy_m`` (N, 2) from every camera."""
        dx = xy_m[:, None, 0] - self.pole_xy_m[None, :, 0]
        dy = xy_m[:, None, 1] - self.pole_xy_m[None, :, 1]
        hx, hy = self.heading[:, 0], self.heading[:, 1]
        return dx * hx + dy * hy, -dx * hy + dy * hx

    def seen_xy(self, xy_m: np.ndarray) -> np.ndarray:
        """(N, C) bool: ground point n (x, y, m) is in camera c's view."""
        forward, lateral = self.forward_lateral_m(np.asarray(xy_m, dtype=np.float64).reshape(-1, 2))
        return ((forward >= self.near_m) & (forward <= self.far_m)
                & (np.abs(lateral) <= forward * self.tan_half_fov))  # fmt: skip

    def seen_sd(self, s_m: float, d_m: float) -> np.ndarray:
        """(C,) bool: street point (s, d) is in each camera's view."""
        return self.seen_xy(np.array([self.frame.to_ground(s_m, d_m)]))[0]

    def interval_s(self, camera: int, s_m: float, d_m: float, sigma_d_m: float = 0.0) -> tuple[float, float] | None:
        """The stretch of street [a, b] (s, m) that camera ``camera`` sees reliably at the offset of a
        road user believed at (s, d): forward distances from where the field of view takes in that
        offset (moved up to ``min(2 sigma_d_m, 1 m)`` toward the camera's axis) or the frame's bottom
        row, whichever is further, to the detector's range, less ``EDGE_M`` at each end; None when
        that is empty or more than 40 m from ``s_m``. The forward distance is taken as linear in s at
        this d (a straight street; the camera looks along it)."""
        x_m, y_m = self.frame.to_ground(s_m, d_m)
        (px, py), (hx, hy) = self._poles[camera], self._headings[camera]
        dx, dy = x_m - px, y_m - py
        f_m, l_m = dx * hx + dy * hy, -dx * hy + dy * hx
        sideways_m = max(abs(l_m) - min(2.0 * sigma_d_m, 1.0), 0.0) / self._tan[camera]
        near_m, far_m = max(self._near[camera], sideways_m) + EDGE_M, self._far[camera] - EDGE_M
        if abs(hx) < 0.5 or near_m >= far_m or f_m < near_m - 40.0 or f_m > far_m + 40.0:
            return None
        a_m, b_m = s_m + (near_m - f_m) / hx, s_m + (far_m - f_m) / hx
        return (a_m, b_m) if a_m <= b_m else (b_m, a_m)

    def visibility(self, camera: int, s_m: float, d_m: float, sigma_s_m: float, sigma_d_m: float = 0.0) -> float:
        """Probability that a road user believed at (s, d), its position along the street uncertain
        by ``sigma_s_m`` (m, one standard deviation), stands where camera ``camera`` sees it
        reliably (``interval_s``)."""
        interval = self.interval_s(camera, s_m, d_m, sigma_d_m)
        if interval is None:
            return 0.0
        sigma = max(sigma_s_m, 1e-3)
        return float(ndtr((interval[1] - s_m) / sigma) - ndtr((interval[0] - s_m) / sigma))


def _near_m(camera) -> float:
    """Ground distance ahead of the pole of the frame's bottom row (its centre pixel), m; 0 when
    the bottom row sees no ground."""
    rays = CameraRays(camera)
    ground = rays.ground_xy_m((camera.width_px - 1) / 2.0, camera.height_px - 0.5)
    if ground is None:
        return 0.0
    dx, dy = ground[0] - rays.px_m, ground[1] - rays.py_m
    return float(dx * camera.heading_unit[0] + dy * camera.heading_unit[1])
