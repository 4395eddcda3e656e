"""A camera's ground detection as a street measurement: position (s, d) and its covariance.

The covariance comes from the camera model: the box's bottom-centre pixel is uncertain by
``SIGMA_U_PX`` across and ``SIGMA_V_PX`` down (a box's bottom row is where segmentation is
least sure: feet, shadows, a car's dark underside), and the pixel-to-ground Jacobian (central
differences of ``CameraRays.ground_xy_m``, lens distortion included) turns that into metres on
the ground. A row near the horizon spans many metres, so the range error grows with distance
(about as distance squared over camera height) and with the bottom row's place in the frame;
the error across the line of sight grows with distance alone. ``FLOOR_M`` is added for the
footprint (where on a body the bottom centre lands).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from citysim.control.camera_rays import CameraRays
from citysim.control.fusion.street_frame import StreetFrame

#: One standard deviation of a box's bottom-centre pixel, across (u) and down (v), px.
SIGMA_U_PX, SIGMA_V_PX = 1.5, 2.0
#: Added standard deviation for where on a body the bottom centre lands, m.
FLOOR_M = 0.3


@dataclass(frozen=True)
class Measurement:
    """One detection on the street: where (s, d; m), how sure (2x2 covariance, m^2), what and whose.

    ``key`` is (camera index, the detector's track id) or None; ``vs_mps`` the detector's own
    velocity along the street when it has one (m/s)."""

    s_m: float
    d_m: float
    cov_m2: np.ndarray
    cls: str
    camera: int
    key: tuple[int, int] | None = None
    vs_mps: float | None = None

    @property
    def z(self) -> np.ndarray:
        return np.array([self.s_m, self.d_m])


def pixel_covariance_m2(rays: CameraRays, u_px: float, v_px: float) -> np.ndarray | None:
    """Ground covariance (x, y; m^2) of the ground point seen at pixel (u, v) (OpenCV pixels)
    when that pixel is uncertain by ``SIGMA_U_PX`` and ``SIGMA_V_PX``; None where the pixel or its
    neighbours see no ground."""
    columns = []
    for du, dv in ((1.0, 0.0), (0.0, 1.0)):
        ahead = rays.ground_xy_m(u_px + du, v_px + dv)
        behind = rays.ground_xy_m(u_px - du, v_px - dv)
        if ahead is None or behind is None:
            return None
        columns.append([(ahead[0] - behind[0]) / 2.0, (ahead[1] - behind[1]) / 2.0])
    jacobian = np.array(columns).T  # d(x, y) / d(u, v), m/px
    pixel_cov = np.diag([SIGMA_U_PX**2, SIGMA_V_PX**2])
    return jacobian @ pixel_cov @ jacobian.T + np.eye(2) * FLOOR_M**2


def measure(frame: StreetFrame, rays: CameraRays, camera: int, detection, cls: str) -> Measurement | None:
    """``detection`` (a ``detector.detector.Detection``) of camera ``camera`` (its ``rays``) as a
    street measurement of class ``cls``; None when its box's bottom sees no ground."""
    x, y, w, h = detection.box_px
    u_px, v_px = x + w / 2 - 0.5, y + h - 0.5
    if detection.ground_x_m is not None:
        ground = (detection.ground_x_m, detection.ground_y_m)
    else:
        ground = rays.ground_xy_m(u_px, v_px)
    if ground is None:
        return None
    cov_xy = pixel_covariance_m2(rays, u_px, v_px)
    if cov_xy is None:
        return None
    jac = frame.jacobian(*ground)
    s_m, d_m = frame.to_street(*ground)
    key = None if detection.track_id is None else (camera, detection.track_id)
    vx = detection.velocity_x_mps
    vs = None if vx is None else float((jac @ np.array([vx, detection.velocity_y_mps or 0.0]))[0])
    return Measurement(s_m, d_m, jac @ cov_xy @ jac.T, cls, camera, key, vs)
