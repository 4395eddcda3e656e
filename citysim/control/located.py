"""Light where people are going: every confirmed target is placed on the street map.

``DetectorLocated`` places each confirmed track of the detector on the street (world x along
the street, y across, m; velocity m/s) and lights the lamp whose zone it stands in and every
lamp whose zone it will enter within its lead time: its own pole's lamp directly, the others
over the simulated network. Lost tracks are extrapolated per class; an end lamp whose approach
no camera watches is kept at full (``light_blind_ends``).

Design: docs/design/modules.md (Lighting where people are going)
"""

from __future__ import annotations

import bisect
import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from citysim.config.motion import MAX_SPEED_MPS
from citysim.control.base import ControlContext
from citysim.control.camera_rays import CameraRays
from citysim.control.detecting import DetectorPerFrame, detection_class
from citysim.control.track_windows import (
    PAPER_K,
    PAPER_N,
    TrackWindows,
    frame_hit,
    keyed_marks,
    windows_wait,
)
from citysim.world.agents import AgentState
from citysim.world.coverage import approaches_seen
from citysim.world.street import Street

#: Extra lead per detector class, s: beyond the ramp and the radio, for what the estimate misses.
CLASS_MARGIN_S = {"pedestrian": 1.0, "group": 1.0, "cyclist": 1.5, "vehicle": 2.0}
#: A lost track is extrapolated this far (m) and this long (s) at most, per class. A walker going -x
#: is lost 6 m before a pole (the forward camera's near edge) and picked up 5 m past it, 15 m before
#: the next zone: 30 m covers that with margin. Cars and bicycles keep their lane from one street end
#: to the other, and the detector loses them often (headlight glare toward the camera, a dark back
#: going away): on suburban_night, seed 1, a car coming toward the cameras was placed by cameras 9
#: and 8 and then by none of the next six, so cars are carried 240 m (eight zones; 20 s at 43 km/h),
#: bicycles 120 m.
EXTRAPOLATE_M = {"pedestrian": 30.0, "group": 30.0, "cyclist": 120.0, "vehicle": 240.0}
EXTRAPOLATE_S = {"pedestrian": 25.0, "group": 25.0, "cyclist": 20.0, "vehicle": 20.0}
#: The detector's velocity of a track is the median of its last this many (one frame's bad bottom row,
#: a car's glare, can give a car coming at 9 m/s a velocity of 2.7 m/s).
VELOCITY_MEDIAN_N = 5
#: Until its velocity is measured, a car or bicycle on a lane is taken to go the lane's way at this
#: speed (m/s; 50 km/h and 22 km/h, the fast end of suburban traffic): the zones ahead are lit from
#: its first confirmed frame, not half a second later.
LANE_PRIOR_MPS = {"vehicle": 50.0 / 3.6, "cyclist": 6.0}
#: A ground point this close to a lane (beyond its edge, m) is on it: cyclists ride near the edge.
LANE_SLACK_M = 0.5
#: Ground positions used for the velocity estimate, s.
VELOCITY_WINDOW_S = 1.0
#: Slower than this along the street, the direction is unknown: light around the position.
STILL_MPS = 0.3
#: Half the stretch lit around a target whose direction is unknown, m.
UNKNOWN_DIRECTION_M = 3.0
#: Faster than any road user plus estimation error: not a target.
IMPLAUSIBLE_MPS = MAX_SPEED_MPS * 1.5


@dataclass
class LocatedTrack:
    """One confirmed target on the street: where it was last seen, and where it is heading."""

    cls: str
    seen: deque = field(default_factory=lambda: deque(maxlen=64))  # (t_s, x_m)
    velocities: deque = field(default_factory=lambda: deque(maxlen=VELOCITY_MEDIAN_N))  # the detector's, m/s
    vx_mps: float | None = None  # along the street; None until known
    prior_vx_mps: float | None = None  # its lane's way at the class's prior speed, until vx_mps is known

    @property
    def heading_vx_mps(self) -> float | None:
        """The measured velocity along the street, else the lane prior, else None (m/s)."""
        return self.vx_mps if self.vx_mps is not None else self.prior_vx_mps

    @property
    def last(self) -> tuple[float, float]:
        return self.seen[-1]

    def observe(self, t_s: float, x_m: float, vx_mps: float | None = None) -> None:
        """One ground position along the street; ``vx_mps`` the detector's velocity when it has one."""
        self.seen.append((t_s, x_m))
        if vx_mps is not None:
            self.velocities.append(vx_mps)
            self.vx_mps = float(np.median(self.velocities))
            return
        recent = self.recent(t_s - VELOCITY_WINDOW_S)
        if len(recent) >= 3 and recent[-1][0] - recent[0][0] >= 0.3:
            t0_s = recent[0][0]  # times from the first: the IEEE subtraction ts - ts[0] made elementwise
            self.vx_mps = line_slope([t_s - t0_s for t_s, _ in recent], [x_m for _, x_m in recent])

    def recent(self, since_s: float) -> list[tuple[float, float]]:
        """The positions seen at ``since_s`` or later, oldest first: a tail of ``seen``, whose times
        never decrease (frames come in time order), found from its end."""
        recent = []
        for seen in reversed(self.seen):
            if seen[0] < since_s:
                break
            recent.append(seen)
        recent.reverse()
        return recent

    def predicted_x_m(self, t_s: float) -> float:
        t_last, x_last = self.last
        return x_last + (self.heading_vx_mps or 0.0) * (t_s - t_last)


def line_slope(x: Sequence[float], y: Sequence[float]) -> float:
    """The slope of ``np.polyfit(x, y, 1)`` (x, y: 1-d float64 arrays, or lists of floats), by its
    steps for a line without the wrappers' checks (~20k fits an hour at 22:00; they were two thirds
    of the cost): the same arrays through the same numpy operations (x + 0.0 and y + 0.0; the
    Vandermonde matrix [x, 1], scaled by its columns' norms; ``np.linalg.lstsq`` with polyfit's
    rcond), so the slope is
    polyfit's bit for bit (the tests compare them). Polyfit's warning for a rank-deficient fit is
    left out: the times here span 0.3 s or more."""
    n = len(x)
    lhs = np.empty((n, 2))  # np.vander(x + 0.0, 2): x, then ones
    lhs[:, 0] = x
    lhs[:, 0] += 0.0  # polyfit's asarray(x) + 0.0 (a -0.0 becomes 0.0)
    lhs[:, 1] = 1.0
    rhs = np.empty((n, 1))  # lstsq's b[:, newaxis] of y + 0.0
    rhs[:, 0] = y
    rhs += 0.0
    scale = np.sqrt(np.add.reduce(lhs * lhs, axis=0))  # what (lhs * lhs).sum(axis=0) calls
    lhs /= scale
    c = np.linalg.lstsq(lhs, rhs, n * _EPS)[0]  # public: numpy's private solver moves between versions
    return float(c[0, 0] / scale[0])


_EPS = float(np.finfo(np.float64).eps)


def blind_end_lamps(street: Street) -> list[int]:
    """The chain's end lamps whose approach no camera watches (``approaches_seen`` under half):
    whoever comes from there enters the end zone before any camera could have seen them."""
    first_seen, last_seen = approaches_seen(street)
    ends = [0] if first_seen < 0.5 else []
    if last_seen < 0.5 and len(street.lamps) - 1 not in ends:
        ends.append(len(street.lamps) - 1)
    return ends


def keep_blind_ends_full(controller, t_s: float) -> None:
    """Re-trigger ``controller``'s ``blind_end_lamps`` (full level) once a simulated second, its
    ``next_blind_end_s`` (s) the next time; shared by ``detector_located`` and ``detector_fused``."""
    if controller.blind_end_lamps and t_s >= controller.next_blind_end_s:
        controller.next_blind_end_s = t_s + 1.0
        for j in controller.blind_end_lamps:
            controller.bank.trigger(j, t_s)


class DetectorLocated(DetectorPerFrame):
    """The detector's confirmed tracks placed on the street; their zones and the zones ahead lit."""

    name = "detector_located"
    tracking = True  # it places the detector's tracks on the street

    @classmethod
    def decisions(cls, spec) -> str:
        # It counts a frame's own decision while the track is plausible, as detector_confirmed does,
        # but fast mode draws it from the track decisions' tables: measured over 1,200 s (seed 1,
        # model v14), the plausible tables' false alarms (10.9 per camera-hour, each placed and lit
        # ahead with a lane's prior speed) made fast detector_located save 22.0 % at 22:00 and
        # 38.1 % at 02:00 against full fidelity's 25.8 % and 52.6 %; the track tables 28.7 % and
        # 52.7 %, lighting the same share of entries on entry (93.9 % and 86.0 %).
        return "track" if cls.decides_per_track(spec) else "frame"

    def __init__(self, ctx: ControlContext):
        super().__init__(ctx)
        self.zone_start_m = np.array([s.zone_start_m for s in ctx.street.lamps])
        self.zone_end_m = np.array([s.zone_end_m for s in ctx.street.lamps])
        self.zone_bounds_m = list(zip(self.zone_start_m.tolist(), self.zone_end_m.tolist(), strict=True))
        self.zone_starts_m, self.zone_ends_m = self.zone_start_m.tolist(), self.zone_end_m.tolist()
        # zones in order along the street (starts and ends ascending): the zones a stretch meets are a run
        self.zones_in_order = self.zone_starts_m == sorted(self.zone_starts_m) and self.zone_ends_m == sorted(
            self.zone_ends_m)  # fmt: skip
        net, lum = ctx.network.spec, ctx.luminaire
        # dim -> full, the radio's worst usual delay, one frame: the lead every class needs
        self.base_lead_s = ((1.0 - lum.dim_level) * lum.ramp_up_s + (net.latency_ms + 3.0 * net.jitter_ms) / 1000.0
                            + ctx.frame_period_s)  # fmt: skip
        if ctx.spec.lead_s is not None:
            self.base_lead_s = ctx.spec.lead_s
        self.repeat_s = net.repeat_s
        self.tracks: dict[tuple[int, int], LocatedTrack] = {}  # (camera, track id) -> track
        self.told_s: dict[tuple[int, int], float] = {}  # (camera lamp, lamp told) -> last message time
        self.next_extrapolation_s = 0.0
        # the windows detector_confirmed keeps per track: a track is placed from its sixth sighting
        # by its frames' classes, not only once its pooled class and velocity call it a target
        full = windows_wait(ctx.sensors)
        self.windows = [TrackWindows(ctx.spec.k or PAPER_K, ctx.spec.n or PAPER_N, full_window=full)
                        for _ in ctx.camera_lamps]  # fmt: skip
        self.ground = [CameraRays(det.camera) for det in self.detectors]
        self.lanes = [(lane.y_center_m - lane.width_m / 2 - LANE_SLACK_M, lane.y_center_m + lane.width_m / 2
                       + LANE_SLACK_M, lane.direction) for lane in ctx.street.lanes]  # fmt: skip
        self.blind_end_lamps = blind_end_lamps(ctx.street) if ctx.spec.light_blind_ends in (None, True) else []
        self.next_blind_end_s = 0.0
        self.camera_lamps = ctx.camera_lamps  # read per placement (the context's property makes the tuple anew)

    def lead_s(self, cls: str) -> float:
        return self.base_lead_s + CLASS_MARGIN_S.get(cls, 1.0)

    def lane_prior_mps(self, cls: str, y_m: float | None) -> float | None:
        """A car's or bicycle's velocity along the street before it is measured: its lane's way at
        the class's prior speed (m/s); None off the lanes or for walkers (they go either way)."""
        speed = LANE_PRIOR_MPS.get(cls)
        if speed is None or y_m is None:
            return None
        ways = {d for lo, hi, d in self.lanes if lo <= y_m <= hi}
        return speed * ways.pop() if len(ways) == 1 else None

    def zones_for(self, x_m: float, vx_mps: float | None, cls: str) -> list[int]:
        """The zones a target at ``x_m`` moving at ``vx_mps`` is in or enters within its lead time."""
        if vx_mps is None or abs(vx_mps) < STILL_MPS:
            lo_m, hi_m = x_m - UNKNOWN_DIRECTION_M, x_m + UNKNOWN_DIRECTION_M
        else:
            ahead_m = vx_mps * self.lead_s(cls)
            lo_m, hi_m = min(x_m, x_m + ahead_m), max(x_m, x_m + ahead_m)
        # plain floats, compared as numpy compared them: a lamp's zone per ~100k placements an hour
        if self.zones_in_order:  # the run of zones ending after lo_m and starting at or before hi_m
            return list(range(bisect.bisect_right(self.zone_ends_m, lo_m), bisect.bisect_right(self.zone_starts_m, hi_m)))
        return [j for j, (start_m, end_m) in enumerate(self.zone_bounds_m) if start_m <= hi_m and end_m > lo_m]

    def light_zones(self, camera_lamp: int, t_s: float, zones: Sequence[int]) -> None:
        """Light ``zones``: the camera's own lamp directly, the others by radio (repeated)."""
        remote = []
        for j in map(int, zones):
            if j == camera_lamp:
                self.bank.trigger(j, t_s)
            elif t_s - self.told_s.get((camera_lamp, j), -math.inf) >= self.repeat_s:
                self.told_s[(camera_lamp, j)] = t_s
                remote.append(j)
        if remote:
            self.ctx.network.send(camera_lamp, remote, "light", {})

    def on_frame(self, camera_index, t_s, image):
        detections = self.detect(camera_index, t_s, image)
        if detections:
            self.place(camera_index, t_s, detections)
        elif detections is not None:  # most judged frames: the windows age (when they hold any), nothing is placed
            window = self.windows[camera_index]
            if window.bits or window.seen:  # else ``update({})`` changes nothing
                window.update({})
        return detections

    def place(self, camera_index: int, t_s: float, detections) -> None:
        """Put camera ``camera_index``'s confirmed target tracks on the street (with that camera's
        pose: its detector's) and light for them from the camera's lamp."""
        det = self.detectors[camera_index]
        window = self.windows[camera_index]
        if not detections:  # most judged frames: the windows age, nothing is placed
            window.update({})
            return
        confirmed = window.update(keyed_marks(detections, det.target_threshold, window)[1])
        for d in detections:
            if d.track_id is None or d.track_id not in confirmed or not frame_hit(d, det.target_threshold):
                continue
            cls = detection_class(d)  # a young track's pooled class says 'noise': its frame's then
            if cls == "noise":
                continue
            if d.ground_x_m is not None:
                ground_x_m, ground_y_m = d.ground_x_m, d.ground_y_m
            else:
                x, y, w, h = d.box_px
                ground = self.ground[camera_index].ground_xy_m(x + w / 2 - 0.5, y + h - 0.5)
                if ground is None:
                    continue
                ground_x_m, ground_y_m = ground
            ground_x_m, ground_y_m, vx_mps = self._on_street(ground_x_m, ground_y_m, d)
            key = (camera_index, d.track_id)
            track = self.tracks.get(key)
            if track is None:
                track = self.tracks[key] = LocatedTrack(cls)
            # a track keeps the class carried furthest it was seen as: a car's class flips to cyclist,
            # group or pedestrian in glare, never the other way for long
            if EXTRAPOLATE_M.get(cls, 0.0) > EXTRAPOLATE_M.get(track.cls, 0.0):
                track.cls = cls
            track.observe(t_s, ground_x_m, vx_mps)
            if track.vx_mps is not None and abs(track.vx_mps) > IMPLAUSIBLE_MPS:
                continue  # nothing on the street moves like that: an insect at the lens, a flicker
            track.prior_vx_mps = self.lane_prior_mps(track.cls, ground_y_m)
            zones = self.zones_for(ground_x_m, track.heading_vx_mps, track.cls)
            self.light_zones(self.camera_lamps[camera_index], t_s, zones)

    def _on_street(self, x_m: float, y_m: float, detection) -> tuple[float, float, float | None]:
        """A ground point (world x, y, m) and the detection's ground velocity in street coordinates:
        (s m, d m, velocity along +s m/s or None); the same numbers on the straight street."""
        line = self.ctx.street.centreline
        vx = detection.velocity_x_mps
        if line.is_straight_x:
            return x_m, y_m, vx
        s_m, d_m = line.to_sd(x_m, y_m)
        if vx is not None:
            vx = float(line.unrotate(s_m, vx, detection.velocity_y_mps or 0.0)[0])
        return s_m, d_m, vx

    def on_physics_step(self, t_s: float, agents: Sequence[AgentState]) -> None:
        super().on_physics_step(t_s, agents)
        keep_blind_ends_full(self, t_s)
        if t_s < self.next_extrapolation_s:
            return
        self.next_extrapolation_s = t_s + 0.25
        stale_after_s = 2.0 * self.ctx.frame_period_s
        for key, track in list(self.tracks.items()):
            gone_s = t_s - track.seen[-1][0]
            if gone_s <= stale_after_s:
                continue  # seen within two frames: neither forgotten nor extrapolated (the checks below)
            vx_mps = track.heading_vx_mps
            travelled_m = abs(vx_mps or 0.0) * gone_s
            if (gone_s > EXTRAPOLATE_S.get(track.cls, 20.0) or travelled_m > EXTRAPOLATE_M.get(track.cls, 20.0)
                    or vx_mps is None):
                del self.tracks[key]
                continue
            if abs(vx_mps) > IMPLAUSIBLE_MPS:
                continue
            self.light_zones(self.camera_lamps[key[0]], t_s,
                             self.zones_for(track.predicted_x_m(t_s), vx_mps, track.cls))

    def on_message(self, lamp_index, t_s, message):
        if message.kind == "light":
            self.bank.trigger(lamp_index, t_s)
