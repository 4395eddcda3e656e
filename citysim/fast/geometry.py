"""Which agents each lamp camera may see, from the agents alone (no rendering).

The sensor model is calibrated and used on the same *candidates*: agents whose footprint centre
lies ahead of a camera within ``CANDIDATE_RANGE_M`` (forward ground distance, m) and within the
camera's horizontal field of view plus a margin. Calibration counts how often the real detector
found each candidate; fast mode draws from those counts, so both sides must agree on who is a
candidate: both call ``CameraGeometry.candidates``.

Conventions: agents come in street coordinates (``x_m`` = s along the centreline, ``y_m`` = d to
its left, heading CCW from +s) and are placed in the world frame (x east, y north, metres) through
``Street.centreline`` before any camera looks at them; on the straight street the two agree. A
camera's *forward* distance is along its heading on the ground; *bearing* is the angle off the
heading, radians, positive to the camera's left (+y when it looks toward +x).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from citysim.control.camera_rays import CameraRays
from citysim.world.agents import AgentState
from citysim.world.placement import columns_in_world
from citysim.world.street import Street

#: Beyond this forward distance nothing is a candidate (the detector ignores what is past 25 m).
CANDIDATE_RANGE_M = 30.0
#: Added to half the horizontal field of view: bodies whose centre is just outside still show.
BEARING_MARGIN_RAD = math.radians(5.0)
#: The wider view that keeps a camera judged every frame (as ``CameraSchedule``'s margin does).
WAKE_RANGE_M = 40.0
WAKE_MARGIN_RAD = math.radians(15.0)
#: Where a road user carrying a light throws it, m ahead of its footprint along its heading: the
#: middle of a dipped beam's 0-20 m on the road (``citysim.fast.records.LIT_REACH_M``).
BEAM_AHEAD_M = 10.0
#: The patch of road a beam lights, as the real detector outlines it (m): a car's spot was 5.5-9 m
#: wide and 2.3-4 m 'tall' at its bottom row; a drawn beam detection is given a box this size.
BEAM_WIDTH_M, BEAM_HEIGHT_M = 6.0, 2.5
#: A camera sees the light pools of lamps this far ahead (m, forward from its pole): beyond its
#: neighbours' (whose ramps its controller waits out), a far lamp switching changes the upper part
#: of the frame, which a whole-frame threshold segmenter takes for foreground.
FAR_VIEW_M = 100.0
#: Added to a road user's object id to name its beam (in calibration rows and fast mode's draws).
BEAM_ID_OFFSET = 1_000_000_000


def beam_id(object_id: int) -> int:
    """The id of the beam of road user ``object_id``: never an agent's own."""
    return BEAM_ID_OFFSET + object_id


def beam_x_m(agent: AgentState) -> float:
    """Where along the street the middle of ``agent``'s beam lies, m."""
    return agent.x_m + BEAM_AHEAD_M * math.cos(agent.heading_rad)


@dataclass(frozen=True)
class Candidates:
    """Per camera, the indices (into the agents list) of its candidates and their geometry."""

    forward_m: np.ndarray  # (A, C) forward ground distance of every agent from every camera
    bearing_rad: np.ndarray  # (A, C)
    seen: np.ndarray  # (A, C) bool: a candidate of that camera
    wake: np.ndarray  # (A, C) bool: within that camera's wider wake view
    #: (A, C) bool: a *beam candidate*: a road user carrying a light, not itself a candidate of that
    #: camera, whose beam's middle (``BEAM_AHEAD_M`` ahead) is in the camera's view; the beam's
    #: forward distance and bearing from that camera (only meant where ``beam_seen``)
    beam_seen: np.ndarray
    beam_forward_m: np.ndarray
    beam_bearing_rad: np.ndarray

    @property
    def awake(self) -> np.ndarray:
        """(C,) bool: something within the camera's wider wake view."""
        return self.wake.any(axis=0)

    def rows(self, first: int, n: int) -> Candidates:
        """The candidates of agents ``first`` to ``first + n`` only (one step's of many steps' rows)."""
        rows = slice(first, first + n)
        return Candidates(self.forward_m[rows], self.bearing_rad[rows], self.seen[rows], self.wake[rows],
                          self.beam_seen[rows], self.beam_forward_m[rows], self.beam_bearing_rad[rows])  # fmt: skip


class CameraGeometry:
    """The lamp cameras' poses as arrays, so one numpy pass places every agent for every camera."""

    def __init__(self, street: Street):
        # every camera of the street (``Street.cameras``: each pole's own, then the backward ones);
        # ``camera_lamps[i]`` is the pole camera i hangs on (lamp levels are read per lamp)
        cams = [site.camera for site in street.cameras]
        self.cameras = cams
        self.camera_lamps: list[int] = list(street.camera_lamps)
        self.n_lamps = len(street.lamps)
        self.rays = [CameraRays(c) for c in cams]
        self.pole_xy_m = np.array([[c.position_m[0], c.position_m[1]] for c in cams], dtype=np.float64)
        self.heading_xy = np.array([[c.heading_unit[0], c.heading_unit[1]] for c in cams], dtype=np.float64)
        self.half_fov_rad = np.array([math.radians(c.horizontal_fov_deg) / 2.0 for c in cams])
        self.line = street.centreline
        self.lamp_x_m = np.array([site.along_m for site in street.lamps], dtype=np.float64)  # s
        # per camera, the lamps ahead within FAR_VIEW_M other than its own pole's and the neighbours'
        poles_xy = np.array([[site.x_m, site.y_m] for site in street.lamps], dtype=np.float64)
        ahead_m, _ = self._view(poles_xy)
        lamp = np.arange(len(poles_xy))
        self.far_lamps = [np.flatnonzero((ahead_m[:, i] > 0.0) & (ahead_m[:, i] <= FAR_VIEW_M)
                                         & (np.abs(lamp - self.camera_lamps[i]) >= 2))
                          for i in range(len(cams))]  # fmt: skip

    @property
    def n(self) -> int:
        return len(self.cameras)

    def candidates(self, agents: Sequence[AgentState]) -> Candidates:
        xy = np.array([[a.x_m, a.y_m] for a in agents], dtype=np.float64).reshape(-1, 2)
        lit = np.array([a.light_on for a in agents], dtype=bool)
        heading = np.array([a.heading_rad for a in agents], dtype=np.float64) if lit.any() else None
        return self.candidates_at(xy, lit, heading)

    def candidates_at(self, xy: np.ndarray, lit: np.ndarray, heading: np.ndarray | None) -> Candidates:
        """``candidates`` of agents standing at ``xy`` (A, 2; street coordinates s, d in m) with their
        lights on where ``lit`` (A,), heading ``heading`` (A,; rad from +s; None when no light is on).
        Every value is elementwise, so the rows of many steps at once give each step's own, bit for bit."""
        if not self.line.is_straight_x:
            x_m, y_m, world_heading = columns_in_world(
                self.line, xy[:, 0], xy[:, 1], np.zeros(len(xy)) if heading is None else heading
            )
            xy = np.column_stack([x_m, y_m])
            heading = None if heading is None else world_heading
        forward, bearing = self._view(xy)
        off = np.abs(bearing)
        seen = (forward > 0.0) & (forward <= CANDIDATE_RANGE_M) & (off <= self.half_fov_rad + BEARING_MARGIN_RAD)
        wake = (forward > 0.0) & (forward <= WAKE_RANGE_M) & (off <= self.half_fov_rad + WAKE_MARGIN_RAD)
        if heading is not None and lit.any():
            beam_xy = xy + BEAM_AHEAD_M * np.column_stack([np.cos(heading), np.sin(heading)])
            beam_forward, beam_bearing = self._view(beam_xy)
            beam_seen = (lit[:, None] & ~seen & (beam_forward > 0.0) & (beam_forward <= CANDIDATE_RANGE_M)
                         & (np.abs(beam_bearing) <= self.half_fov_rad + BEARING_MARGIN_RAD))  # fmt: skip
        else:
            beam_forward, beam_bearing, beam_seen = forward, bearing, np.zeros_like(seen)
        return Candidates(forward, bearing, seen, wake, beam_seen, beam_forward, beam_bearing)

    def _view(self, xy_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(A, C) forward ground distance (m) and bearing (rad) of ground points from every camera."""
        dx = xy_m[:, None, 0] - self.pole_xy_m[None, :, 0]
        dy = xy_m[:, None, 1] - self.pole_xy_m[None, :, 1]
        hx, hy = self.heading_xy[:, 0], self.heading_xy[:, 1]
        forward = dx * hx + dy * hy
        lateral = -dx * hy + dy * hx
        return forward, np.arctan2(lateral, forward)

    def nearest_lamp(self, x_m: np.ndarray) -> np.ndarray:
        """The index of the lamp nearest along the street to each ``x_m``."""
        return np.abs(np.asarray(x_m, dtype=np.float64)[:, None] - self.lamp_x_m[None, :]).argmin(axis=1)

    def light_at(self, x_m: np.ndarray, levels: np.ndarray) -> np.ndarray:
        """The level (0..1) of the lamp nearest along the street to each ``x_m``."""
        return np.asarray(levels, dtype=np.float64)[self.nearest_lamp(x_m)]

    def beam_box_px(self, lamp_index: int, agent: AgentState, ahead_m: float = BEAM_AHEAD_M) -> tuple[int, int, int, int]:
        """The box of the patch ``agent``'s light throws ``ahead_m`` ahead of it, in camera
        ``lamp_index``'s frame (px; as ``box_px``, standing on the patch's middle)."""
        x_m, y_m, heading = agent.x_m, agent.y_m, agent.heading_rad
        if not self.line.is_straight_x:
            x_m, y_m = self.line.to_xy(x_m, y_m)
            heading = heading + self.line.heading_rad(agent.x_m)
        x_m = x_m + ahead_m * math.cos(heading)
        y_m = y_m + ahead_m * math.sin(heading)
        spot = AgentState(agent.object_id, agent.cls, x_m, y_m, heading, agent.speed_mps, BEAM_WIDTH_M,
                          BEAM_WIDTH_M, BEAM_HEIGHT_M)  # fmt: skip
        return self._boxes_px(lamp_index, [spot], placed=True)[0]

    def box_px(self, lamp_index: int, agent: AgentState) -> tuple[int, int, int, int]:
        """An OpenCV (x, y, w, h) box of ``agent`` in camera ``lamp_index``'s distorted frame, px:
        its bottom centre is the footprint centre's pixel, so ``pixel_to_ground`` puts it back there."""
        return self.boxes_px(lamp_index, [agent])[0]

    def boxes_px(self, lamp_index: int, agents: Sequence[AgentState]) -> list[tuple[int, int, int, int]]:
        """``box_px`` of each of ``agents`` in camera ``lamp_index``, their points projected in one call."""
        return self._boxes_px(lamp_index, agents, placed=self.line.is_straight_x)

    def _boxes_px(self, lamp_index: int, agents: Sequence, placed: bool) -> list[tuple[int, int, int, int]]:
        """``boxes_px`` of agents in street coordinates, or in the world frame when ``placed``."""
        # per agent its footprint centre and the point above it at its height, (2 N, 3)
        pts = np.array([v for a in agents for v in (a.x_m, a.y_m, 0.0, a.x_m, a.y_m, a.height_m)],
                       dtype=np.float64).reshape(-1, 3)  # fmt: skip
        if not placed:  # a few agents at a time: one float conversion each
            for n, agent in enumerate(agents):
                pts[2 * n, :2] = pts[2 * n + 1, :2] = self.line.to_xy(float(agent.x_m), float(agent.y_m))
        uv = self.rays[lamp_index].project_px(pts)  # the camera's ``project``, its per-call cost left out
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


class LevelChanges:
    """When each lamp's level last changed, from the levels seen at successive times: how long ago a
    camera's far lamps (``CameraGeometry.far_lamps``) last changed, s. Calibration records it and
    fast mode keys the threshold samples by it: a far lamp's pool switching leaves foreground in
    the top of the frame until the background has learnt it (calibration: 69 % of the frames with
    nothing in view held a region over 0.5 % of the frame within 2 s of the change, 17 % after
    10-20 s, 2 % after 20-40 s)."""

    def __init__(self, geometry: CameraGeometry):
        self.far_lamps = geometry.far_lamps
        self.changed_at_s = np.full(geometry.n_lamps, -np.inf)  # per lamp
        self.levels: np.ndarray | None = None
        self._seen_levels: np.ndarray | None = None
        #: per camera, when a lamp in its far view last changed (None: no far lamps); None: not known yet
        self._last_far_change_s: list | None = None

    def update(self, t_s: float, levels: np.ndarray) -> None:
        if levels is self._seen_levels:  # the same read-only array (``LampStates``): no level changed
            return
        self._seen_levels = None if levels.flags.writeable else levels
        if self.levels is not None:
            changed = levels != self.levels
            if changed.any():
                self.changed_at_s[changed] = t_s
                self._last_far_change_s = None
        self.levels = np.array(levels, dtype=np.float64)

    def far_change_age_s(self, camera: int, t_s: float) -> float:
        """Seconds since a lamp in camera ``camera``'s far view last changed level (inf: never seen to)."""
        if self._last_far_change_s is None:  # per camera, once per change: asked by every idle judged frame
            self._last_far_change_s = [self.changed_at_s[far].max() if len(far) else None for far in self.far_lamps]
        last_s = self._last_far_change_s[camera]
        return float(t_s - last_s) if last_s is not None else math.inf
