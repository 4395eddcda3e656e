"""``detector_fused``: one street track per road user from every camera, lamps lit by the probability of arrival.

Every judged frame of every camera feeds the street tracker (``citysim.control.fusion``): the
frame's detections of target tracks (``Detector.is_target``: plausible ground motion and size,
pooled P(target) over the threshold; the decisions fast mode's track tables are calibrated on,
so both fidelities feed the tracker alike) become street measurements with the camera model's uncertainty, and
a frame that shows nothing where a track should be lowers that track's existence. Each decision
step (one camera frame) the controller computes, per lamp zone, the probability that some track
is in the zone or enters it within the lead (the lamp's ramp from dim, the radio's latency plus
three jitters, one frame, one decision step, and a class margin, ``located.CLASS_MARGIN_S``),
and lights every zone where that probability reaches ``zone_probability`` (a controller field and
sweep axis, default ``DEFAULT_ZONE_PROBABILITY``). A lamp is released by the same rule: once no
decision keeps it, after the hold time. The lamp of the camera that last saw the deciding track
switches its own zone directly and tells the others over the radio (repeated every
``network.repeat_s``), as ``detector_located`` does; an end lamp whose approach no camera watches
is kept at full (``light_blind_ends``). Fusion itself is taken to share detections instantly.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from citysim.config.motion import MAX_SPEED_MPS
from citysim.control.base import ControlContext
from citysim.control.camera_rays import CameraRays
from citysim.control.detecting import DetectorPerFrame, detection_class
from citysim.control.fusion.births import BirthMap
from citysim.control.fusion.measurement import Measurement, measure
from citysim.control.fusion.street_frame import StreetFrame
from citysim.control.fusion.tracker import StreetTracker
from citysim.control.fusion.views import CameraViews
from citysim.control.fusion.zones import zone_probabilities
from citysim.control.located import (
    CLASS_MARGIN_S,
    LANE_PRIOR_MPS,
    LANE_SLACK_M,
    blind_end_lamps,
    keep_blind_ends_full,
)
from citysim.control.track_windows import frame_hit
from citysim.world.agents import AgentState

#: Light a zone while P(some track is in it or enters it within the lead) reaches this.
DEFAULT_ZONE_PROBABILITY = 0.3
#: Faster than any road user plus estimation error: not a target (m/s).
IMPLAUSIBLE_MPS = MAX_SPEED_MPS * 1.5


class DetectorFused(DetectorPerFrame):
    """Every camera's detections fused into street tracks; zones lit while P(arrival) >= a threshold."""

    name = "detector_fused"
    tracking = True

    @classmethod
    def decisions(cls, spec) -> str:
        # fast mode draws from the track decisions' tables, as for detector_located
        return "track" if cls.decides_per_track(spec) else "frame"

    def __init__(self, ctx: ControlContext):
        super().__init__(ctx)
        street = ctx.street
        self.frame = StreetFrame.of(street)
        cameras = [det.camera for det in self.detectors]
        self.rays = [CameraRays(c) for c in cameras]
        self.views = CameraViews(cameras, self.frame)
        lateral_m = [lane.y_center_m for lane in street.lanes] + [w.y_center_m for w in street.sidewalks]
        self.tracker = StreetTracker(self.frame, self.views, BirthMap(self.views, street.length_m, lateral_m or [0.0]),
                                     self.lane_speed)  # fmt: skip
        self.zone_start_m = np.array([s.zone_start_m for s in street.lamps])
        self.zone_end_m = np.array([s.zone_end_m for s in street.lamps])
        self.threshold = DEFAULT_ZONE_PROBABILITY if ctx.spec.zone_probability is None else ctx.spec.zone_probability
        net, lum = ctx.network.spec, ctx.luminaire
        self.decide_every_s = ctx.frame_period_s
        self.base_lead_s = ((1.0 - lum.dim_level) * lum.ramp_up_s + (net.latency_ms + 3.0 * net.jitter_ms) / 1000.0
                            + ctx.frame_period_s + self.decide_every_s)  # fmt: skip
        if ctx.spec.lead_s is not None:
            self.base_lead_s = ctx.spec.lead_s
        self.lanes = [(lane.y_center_m - lane.width_m / 2 - LANE_SLACK_M, lane.y_center_m + lane.width_m / 2
                       + LANE_SLACK_M, lane.direction) for lane in street.lanes]  # fmt: skip
        self.repeat_s = net.repeat_s
        self.told_s: dict[tuple[int, int], float] = {}
        self.blind_end_lamps = blind_end_lamps(street) if ctx.spec.light_blind_ends in (None, True) else []
        self.next_blind_end_s = 0.0
        self.next_decision_s = 0.0
        self.camera_lamps = ctx.camera_lamps

    def lead_s(self, cls: str) -> float:
        """How far ahead a track of class ``cls`` lights, s."""
        return self.base_lead_s + CLASS_MARGIN_S.get(cls, 1.0)

    def lane_speed(self, cls: str, d_m: float) -> float | None:
        """A newborn car's or bicycle's speed along the street from its lane's way (m/s); None off the lanes."""
        speed = LANE_PRIOR_MPS.get(cls)
        if speed is None:
            return None
        ways = {way for lo, hi, way in self.lanes if lo <= d_m <= hi}
        return speed * ways.pop() if len(ways) == 1 else None

    def measurements(self, camera_index: int, detections) -> list[Measurement]:
        """The frame's target detections as street measurements."""
        det = self.detectors[camera_index]
        out = []
        for d in detections:
            # a target by its track's decision (the track tables fast mode draws from), never a still region
            if frame_hit(d, det.target_threshold) is not True or not det.is_target([d]):
                continue
            cls = detection_class(d)
            if cls == "noise" or (d.velocity_x_mps is not None and abs(d.velocity_x_mps) > IMPLAUSIBLE_MPS):
                continue
            m = measure(self.frame, self.rays[camera_index], camera_index, d, cls)
            if m is not None:
                out.append(m)
        return out

    def on_frame(self, camera_index, t_s, image):
        detections = self.detect(camera_index, t_s, image)
        if detections is None:  # not judged (the light in view was changing): no evidence either way
            return None
        self.tracker.observe(camera_index, t_s, self.measurements(camera_index, detections) if detections else [])
        return detections

    def on_physics_step(self, t_s: float, agents: Sequence[AgentState]) -> None:
        super().on_physics_step(t_s, agents)
        keep_blind_ends_full(self, t_s)
        if t_s < self.next_decision_s:
            return
        self.next_decision_s = t_s + self.decide_every_s
        if not self.tracker.tracks:
            return
        self.tracker.prune(t_s)
        tracks = self.tracker.tracks
        p, best = zone_probabilities(tracks, self.lead_s, self.zone_start_m, self.zone_end_m)
        remote: dict[int, list[int]] = {}
        for j in np.flatnonzero(p >= self.threshold).tolist():
            sender = self.camera_lamps[tracks[int(best[j])].last_camera]
            if j == sender:
                self.bank.trigger(j, t_s)
            elif t_s - self.told_s.get((sender, j), -math.inf) >= self.repeat_s:
                self.told_s[(sender, j)] = t_s
                remote.setdefault(sender, []).append(j)
        for sender, zones in remote.items():
            self.ctx.network.send(sender, zones, "light", {})

    def on_message(self, lamp_index, t_s, message):
        if message.kind == "light":
            self.bank.trigger(lamp_index, t_s)
