"""Light where people are going: every confirmed target is placed on the street map.

A lamp camera sees 6-25 m ahead, which is mostly the next lamp's zone, so lighting only the
camera's own lamp lights the wrong stretch. ``DetectorLocated`` takes each confirmed target
track of the detector (a target track in k of its last n frames: ``TrackWindows``, as
``detector_confirmed``), takes its ground position and velocity from the detector's track
(``detector.tracks``: the bottom-centre pixel through the camera model, world x along the
street, y across, m; velocity over the track's last half second; detections without a track
are placed with ``pixel_to_ground`` and their velocity fitted over the last second here), and
lights:

* the lamp whose zone it stands in, and
* every lamp whose zone it will enter within its lead time: the lamp's ramp, the radio's
  latency and jitter, one camera frame and a class margin (a vehicle at 60 km/h needs several
  zones ahead lit before it arrives).

The camera's own lamp is switched directly; others are told over the simulated network (its
latency, jitter and loss apply), a message repeated every ``network.repeat_s`` while the need
lasts. Each lamp is released once nothing located is in or heading into its zone, plus the
hold time. A track lost from view (it left the camera's 25 m, or walks under the pole where no
camera looks) is extrapolated at its last velocity for a bounded distance and time, so the
zones it walks into are lit before another camera picks it up. A track whose ground speed is
beyond any road user's (an insect near the lens seen as far away and fast) is not a target:
the detector's tracks already reject those (``detector.tracks.plausibility``); the check here
stays for detections without a track.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from citysim.config.motion import MAX_SPEED_MPS
from citysim.control.base import ControlContext
from citysim.control.detecting import DetectorPerFrame, TrackWindows
from citysim.world.agents import AgentState

#: Extra lead per detector class, s: beyond the ramp and the radio, for what the estimate misses.
CLASS_MARGIN_S = {"pedestrian": 1.0, "group": 1.0, "cyclist": 1.5, "vehicle": 2.0}
#: A lost track is extrapolated this far and this long at most (the blind stretch under a pole is ~12 m).
EXTRAPOLATE_M = 20.0
EXTRAPOLATE_S = 20.0
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
    vx_mps: float | None = None  # along the street; None until known

    @property
    def last(self) -> tuple[float, float]:
        return self.seen[-1]

    def observe(self, t_s: float, x_m: float, vx_mps: float | None = None) -> None:
        """One ground position along the street; ``vx_mps`` the detector's velocity when it has one."""
        self.seen.append((t_s, x_m))
        if vx_mps is not None:
            self.vx_mps = vx_mps
            return
        recent = [(t, x) for t, x in self.seen if t >= t_s - VELOCITY_WINDOW_S]
        if len(recent) >= 3 and recent[-1][0] - recent[0][0] >= 0.3:
            ts, xs = np.array(recent).T
            self.vx_mps = float(np.polyfit(ts - ts[0], xs, 1)[0])

    def predicted_x_m(self, t_s: float) -> float:
        t_last, x_last = self.last
        return x_last + (self.vx_mps or 0.0) * (t_s - t_last)


class DetectorLocated(DetectorPerFrame):
    """The detector's confirmed tracks placed on the street; their zones and the zones ahead lit."""

    name = "detector_located"
    tracking = True  # it places the detector's tracks on the street

    def __init__(self, ctx: ControlContext):
        super().__init__(ctx)
        self.zone_start_m = np.array([s.zone_start_m for s in ctx.street.lamps])
        self.zone_end_m = np.array([s.zone_end_m for s in ctx.street.lamps])
        net, lum = ctx.network.spec, ctx.luminaire
        # dim -> full, the radio's worst usual delay, one frame: the lead every class needs
        self.base_lead_s = ((1.0 - lum.dim_level) * lum.ramp_up_s + (net.latency_ms + 3.0 * net.jitter_ms) / 1000.0
                            + ctx.frame_period_s)  # fmt: skip
        if ctx.spec.lead_s is not None:
            self.base_lead_s = ctx.spec.lead_s
        self.repeat_s = net.repeat_s
        self.tracks: dict[tuple[int, int], LocatedTrack] = {}
        self.told_s: dict[tuple[int, int], float] = {}  # (camera lamp, lamp told) -> last message time
        self.next_extrapolation_s = 0.0
        self.windows = [TrackWindows(ctx.spec.k or 2, ctx.spec.n or 6) for _ in ctx.lamps]

    def lead_s(self, cls: str) -> float:
        return self.base_lead_s + CLASS_MARGIN_S.get(cls, 1.0)

    def zones_for(self, x_m: float, vx_mps: float | None, cls: str) -> np.ndarray:
        """The zones a target at ``x_m`` moving at ``vx_mps`` is in or enters within its lead time."""
        if vx_mps is None or abs(vx_mps) < STILL_MPS:
            lo_m, hi_m = x_m - UNKNOWN_DIRECTION_M, x_m + UNKNOWN_DIRECTION_M
        else:
            ahead_m = vx_mps * self.lead_s(cls)
            lo_m, hi_m = min(x_m, x_m + ahead_m), max(x_m, x_m + ahead_m)
        return np.flatnonzero((self.zone_start_m <= hi_m) & (self.zone_end_m > lo_m))

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

    def on_frame(self, lamp_index, t_s, image):
        detections = self.detect(lamp_index, t_s, image)
        if detections is not None:
            self.place(lamp_index, t_s, detections)
        return detections

    def place(self, lamp_index: int, t_s: float, detections) -> None:
        """Put camera ``lamp_index``'s confirmed target tracks on the street and light for them."""
        det = self.detectors[lamp_index]
        cam = det.camera
        hits: dict = {}
        for d in detections:
            hits[d.track_id] = hits.get(d.track_id, False) or det.is_target([d])
        confirmed = self.windows[lamp_index].update(hits)
        for d in detections:
            if d.track_id is None or d.track_id not in confirmed or not det.is_target([d]):
                continue
            cls = d.track_cls if d.track_cls is not None else d.cls
            if cls == "noise":
                continue
            if d.ground_x_m is not None:
                ground_x_m = d.ground_x_m
            else:
                x, y, w, h = d.box_px
                ground = cam.pixel_to_ground(np.array([[x + w / 2 - 0.5, y + h - 0.5]], dtype=np.float64))[0]
                if not np.all(np.isfinite(ground)):
                    continue
                ground_x_m = float(ground[0])
            key = (lamp_index, d.track_id)
            track = self.tracks.setdefault(key, LocatedTrack(cls))
            track.cls = cls
            track.observe(t_s, ground_x_m, d.velocity_x_mps)
            if track.vx_mps is not None and abs(track.vx_mps) > IMPLAUSIBLE_MPS:
                continue  # nothing on the street moves like that: an insect at the lens, a flicker
            self.light_zones(lamp_index, t_s, self.zones_for(ground_x_m, track.vx_mps, track.cls))

    def on_physics_step(self, t_s: float, agents: Sequence[AgentState]) -> None:
        super().on_physics_step(t_s, agents)
        if t_s < self.next_extrapolation_s:
            return
        self.next_extrapolation_s = t_s + 0.25
        stale_after_s = 2.0 * self.ctx.frame_period_s
        for key, track in list(self.tracks.items()):
            t_last, _ = track.last
            gone_s = t_s - t_last
            travelled_m = abs(track.vx_mps or 0.0) * gone_s
            if gone_s > EXTRAPOLATE_S or travelled_m > EXTRAPOLATE_M or track.vx_mps is None:
                if gone_s > stale_after_s:
                    del self.tracks[key]
                continue
            if gone_s <= stale_after_s or abs(track.vx_mps) > IMPLAUSIBLE_MPS:
                continue
            self.light_zones(key[0], t_s, self.zones_for(track.predicted_x_m(t_s), track.vx_mps, track.cls))

    def on_message(self, lamp_index, t_s, message):
        if message.kind == "light":
            self.bank.trigger(lamp_index, t_s)
