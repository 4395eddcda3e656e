"""A camera's ground point of a box's bottom centre, remembered per pixel.

``DetectorLocated`` places each confirmed detection without a ground position (fast mode's drawn
ones) with ``CameraModel.pixel_to_ground`` of its box's bottom centre: an OpenCV iterative
undistortion and a ray cast, ~40 us a call, ~20k calls an hour at 22:00. Boxes are whole pixels,
so the same bottom centres come back again and again (road users keep their lanes): the answer
for a pixel is kept, the same call's result, so the ground points are the same bit for bit.
"""

from __future__ import annotations

import numpy as np

#: Pixels remembered per camera before the memo starts over (bounds its memory).
MAX_PIXELS = 50_000


class GroundMemo:
    """``pixel_to_ground`` of one camera, remembered per pixel (u, v; px)."""

    def __init__(self, camera):
        self.camera = camera
        self._ground: dict[tuple[float, float], tuple[float, float] | None] = {}

    def ground_xy_m(self, u_px: float, v_px: float) -> tuple[float, float] | None:
        """World (x, y) of the ground point seen at pixel (u, v), m; None: no ground point there."""
        key = (u_px, v_px)
        if key in self._ground:
            return self._ground[key]
        if len(self._ground) >= MAX_PIXELS:
            self._ground.clear()
        ground = self.camera.pixel_to_ground(np.array([[u_px, v_px]], dtype=np.float64))[0]
        xy = (float(ground[0]), float(ground[1])) if np.all(np.isfinite(ground)) else None
        self._ground[key] = xy
        return xy
