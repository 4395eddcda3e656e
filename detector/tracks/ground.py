"""Where on the ground a region stands: the bottom centre of its box through the camera.

Conventions: boxes are OpenCV ``(x, y, w, h)`` pixels of the distorted frame with pixel
centres on integers (as ``detector.features``), so the bottom centre of a box is the
continuous point ``(x + w / 2 - 0.5, y + h - 0.5)``. Ground positions come out in the
camera's ground frame: ``forward_m`` along its heading from the pole foot (the paper's
eq. 4 distance) and ``right_m`` to the right of the heading; ``to_world`` turns them into the
world's x (along the street) and y (across), m. One undistortion call per frame, then plain
Python per region (a frame holds a handful).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from detector.camera import MIN_DEPRESSION_RAD, CameraModel
from detector.features import RegionGeometry


class GroundProjector:
    """One camera's pixel -> ground constants, for the bottom centres of region boxes."""

    def __init__(self, camera: CameraModel, geometry: RegionGeometry | None = None) -> None:
        self.geometry = RegionGeometry(camera) if geometry is None else geometry
        self.height_m = camera.height_m
        self.tilt_rad = math.radians(camera.tilt_deg)
        self.sin_tilt, self.cos_tilt = math.sin(self.tilt_rad), math.cos(self.tilt_rad)
        self.cx_px, self.cy_px = camera.cx_px, camera.cy_px
        self.fx_px, self.fy_px = camera.fx_px, camera.fy_px
        yaw = math.radians(camera.yaw_deg)
        self.pole_x_m, self.pole_y_m = camera.x_m, camera.y_m
        self.cos_yaw, self.sin_yaw = math.cos(yaw), math.sin(yaw)

    def bottom_centres(self, boxes_px: Sequence[Sequence[float]]) -> list[tuple[float, float] | None]:
        """(forward_m, right_m) of each box's bottom centre; None where it has no ground point."""
        if not boxes_px:
            return []
        distorted = self.geometry.distorted
        if distorted:
            centres_px = [(x + w / 2 - 0.5, y + h - 0.5) for x, y, w, h in boxes_px]
            undistorted_px = self.geometry.undistort(np.array(centres_px, np.float64)).tolist()
        out: list[tuple[float, float] | None] = []
        # the bottom centres taken in this loop, not listed first, where the lens does not distort
        for k, (x, y, w, h) in enumerate(boxes_px):
            u, v = undistorted_px[k] if distorted else (x + w / 2 - 0.5, y + h - 0.5)
            b = (v - self.cy_px) / self.fy_px
            alpha = self.tilt_rad + math.atan(b)
            if not alpha > MIN_DEPRESSION_RAD:
                out.append(None)
                continue
            forward_m = self.height_m / math.tan(alpha)
            # camera-frame depth of the ground point; camera x is horizontal (roll 0)
            z_cam_m = self.height_m / (self.sin_tilt + b * self.cos_tilt)
            out.append((forward_m, z_cam_m * (u - self.cx_px) / self.fx_px))
        return out

    def to_world(self, forward_m: float, right_m: float) -> tuple[float, float]:
        """Camera ground frame -> world (x_m, y_m); the heading's right is (sin yaw, -cos yaw)."""
        c, s = self.cos_yaw, self.sin_yaw
        return (self.pole_x_m + forward_m * c + right_m * s, self.pole_y_m + forward_m * s - right_m * c)

    def velocity_to_world(self, forward_mps: float, right_mps: float) -> tuple[float, float]:
        """A ground velocity from the camera's frame to the world's (x, y), m/s."""
        c, s = self.cos_yaw, self.sin_yaw
        return (forward_mps * c + right_mps * s, forward_mps * s - right_mps * c)


def line_of_sight_cos(vf_mps: float, vr_mps: float, speed_mps: float, forward_m: float,
                      right_m: float) -> float | None:  # fmt: skip
    """Cosine between a ground velocity (``vf_mps`` forward, ``vr_mps`` right, of length
    ``speed_mps``) and the line of sight from the pole foot to the ground point (``forward_m``,
    ``right_m``), all in the camera's ground frame: 1 going straight away from the camera, -1
    coming straight at it; None when the velocity or the distance is zero."""
    reach_m = math.hypot(forward_m, right_m)
    if speed_mps <= 0.0 or reach_m <= 0.0:
        return None
    return (vf_mps * forward_m + vr_mps * right_m) / (speed_mps * reach_m)
