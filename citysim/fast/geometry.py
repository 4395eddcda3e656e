"""Which agents each lamp camera may see, from the agents alone (no rendering).

The sensor model is calibrated and used on the same *candidates*: agents whose footprint centre
lies ahead of a camera within ``CANDIDATE_RANGE_M`` (forward ground distance, m) and within the
camera's horizontal field of view plus a margin. Calibration counts how often the real detector
found each candidate; fast mode draws from those counts, so both sides must agree on who is a
candidate: both call ``CameraGeometry.candidates``.

Conventions: world x along the street, y across it, metres. A camera's *forward* distance is
along its heading on the ground; *bearing* is the angle off the heading, radians, positive to
the camera's left (+y when it looks toward +x).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from citysim.world.agents import AgentState
from citysim.world.street import Street

#: Beyond this forward distance nothing is a candidate (the detector ignores what is past 25 m).
CANDIDATE_RANGE_M = 30.0
#: Added to half the horizontal field of view: bodies whose centre is just outside still show.
BEARING_MARGIN_RAD = math.radians(5.0)
#: The wider view that keeps a camera judged every frame (as ``CameraSchedule``'s margin does).
WAKE_RANGE_M = 40.0
WAKE_MARGIN_RAD = math.radians(15.0)


@dataclass(frozen=True)
class Candidates:
    """Per camera, the indices (into the agents list) of its candidates and their geometry."""

    forward_m: np.ndarray  # (A, C) forward ground distance of every agent from every camera
    bearing_rad: np.ndarray  # (A, C)
    seen: np.ndarray  # (A, C) bool: a candidate of that camera
    awake: np.ndarray  # (C,) bool: something within the wider wake view


class CameraGeometry:
    """The lamp cameras' poses as arrays, so one numpy pass places every agent for every camera."""

    def __init__(self, street: Street):
        cams = [site.camera for site in street.lamps]
        self.cameras = cams
        self.pole_xy_m = np.array([[c.position_m[0], c.position_m[1]] for c in cams], dtype=np.float64)
        self.heading_xy = np.array([[c.heading_unit[0], c.heading_unit[1]] for c in cams], dtype=np.float64)
        self.half_fov_rad = np.array([math.radians(c.horizontal_fov_deg) / 2.0 for c in cams])
        self.lamp_x_m = np.array([site.x_m for site in street.lamps], dtype=np.float64)

    @property
    def n(self) -> int:
        return len(self.cameras)

    def candidates(self, agents: Sequence[AgentState]) -> Candidates:
        xy = np.array([[a.x_m, a.y_m] for a in agents], dtype=np.float64).reshape(-1, 2)
        dx = xy[:, None, 0] - self.pole_xy_m[None, :, 0]
        dy = xy[:, None, 1] - self.pole_xy_m[None, :, 1]
        hx, hy = self.heading_xy[:, 0], self.heading_xy[:, 1]
        forward = dx * hx + dy * hy
        lateral = -dx * hy + dy * hx
        bearing = np.arctan2(lateral, forward)
        off = np.abs(bearing)
        seen = (forward > 0.0) & (forward <= CANDIDATE_RANGE_M) & (off <= self.half_fov_rad + BEARING_MARGIN_RAD)
        wake = (forward > 0.0) & (forward <= WAKE_RANGE_M) & (off <= self.half_fov_rad + WAKE_MARGIN_RAD)
        return Candidates(forward, bearing, seen, wake.any(axis=0) if len(xy) else np.zeros(self.n, bool))

    def light_at(self, x_m: np.ndarray, levels: np.ndarray) -> np.ndarray:
        """The level (0..1) of the lamp nearest along the street to each ``x_m``."""
        nearest = np.abs(np.asarray(x_m, dtype=np.float64)[:, None] - self.lamp_x_m[None, :]).argmin(axis=1)
        return np.asarray(levels, dtype=np.float64)[nearest]

    def box_px(self, lamp_index: int, agent: AgentState) -> tuple[int, int, int, int]:
        """An OpenCV (x, y, w, h) box of ``agent`` in camera ``lamp_index``'s distorted frame, px:
        its bottom centre is the footprint centre's pixel, so ``pixel_to_ground`` puts it back there."""
        return self.boxes_px(lamp_index, [agent])[0]

    def boxes_px(self, lamp_index: int, agents: Sequence[AgentState]) -> list[tuple[int, int, int, int]]:
        """``box_px`` of each of ``agents`` in camera ``lamp_index``, their points projected in one call."""
        cam = self.cameras[lamp_index]
        pts = np.array([p for a in agents for p in ((a.x_m, a.y_m, 0.0), (a.x_m, a.y_m, a.height_m))],
                       dtype=np.float64).reshape(-1, 3)  # fmt: skip
        uv = cam.project(pts).tolist()
        boxes = []
        for n, agent in enumerate(agents):
            (u0, v0), (_, v1) = uv[2 * n], uv[2 * n + 1]
            if not (math.isfinite(u0) and math.isfinite(v0) and math.isfinite(v1)):
                boxes.append((0, 0, 1, 1))
                continue
            h = max(2.0, v0 - v1)
            w = max(2.0, h * max(agent.width_m, 0.3) / max(agent.height_m, 0.3))
            boxes.append((int(round(u0 - w / 2)), int(round(v0 - h)), int(round(w)), int(round(h))))
        return boxes
