"""The paper's detector driving the lamps: per frame, confirmed k of n per track, and told to neighbours.

``detector`` decides per frame, as the paper does: any target in the frame lights the lamp.
``detector_confirmed`` and ``detector_network`` run the detector with tracks (``detector.tracks``)
and ask the paper's k of the last n frames *of one track* (``citysim.control.track_windows``): a
frame counts by its own class unless a physics rule rules its track out, so an insect here and a
flicker there no longer add up to a confirmation, while a car is confirmed as soon as it has been
seen in n frames. ``detector_tracked`` (and ``detector_located``) count only frames of a track
already judged a target (plausible, pooled P(target) >= threshold; ``Detector.is_target``). A
scenario's controller spec may set ``tracking: false`` for the paper's one window per frame.
"""

from __future__ import annotations

import math

import numpy as np

from citysim.config.kinds import AGENT_KINDS
from citysim.control.base import Controller
from citysim.control.camera import BackgroundClock, LightChangeWatch
from citysim.control.track_windows import (
    PAPER_K,
    PAPER_N,
    TrackWindows,
    frame_hit,
    keyed_marks,
    windows_wait,
)


def detection_class(d) -> str:
    """A detection's class: its track's pooled one when its track is a target, else its frame's
    (a track not yet judged is 'noise' by its pooled class, but its frame may say 'vehicle')."""
    return d.track_cls if d.track_target else d.cls


class DetectorPerFrame(Controller):
    """The paper's detector, deciding per frame on the target group."""

    name = "detector"
    uses_camera = True
    #: decide per track (``detector.tracks``) rather than per frame; the scenario's controller
    #: spec may override it. Off for the paper's frame-by-frame detector; detector_confirmed and
    #: its kin keep their k-of-n windows per track (``citysim.control.track_windows``).
    tracking = False

    def __init__(self, ctx):
        super().__init__(ctx)
        threshold = 0.5 if ctx.spec.target_threshold is None else ctx.spec.target_threshold
        if ctx.sensors is not None:  # fast mode: a calibrated sensor model with the Detector's interface
            self.detectors = ctx.sensors.detectors(ctx, threshold)
        else:
            from detector.detector import Detector
            from detector.general_model import default_model

            model = default_model()
            tracking = self.decides_per_track(ctx.spec)
            # one detector per camera, with that camera's pose: its ground positions are the street's
            self.detectors = [Detector(site.camera, model=model, target_threshold=threshold, tracking=tracking)
                              for site in ctx.street.cameras]  # fmt: skip
        self.light = LightChangeWatch(ctx)
        self.clock = BackgroundClock(len(ctx.camera_lamps), 1.0 / ctx.frame_period_s)

    def motion_seen(self, camera_index):
        return self.detectors[camera_index].motion_in_band

    def cameras_in_motion(self) -> list[bool]:
        """``motion_seen`` of every camera at once (fast mode's sense loop asks every frame)."""
        return [det.motion_in_band for det in self.detectors]

    def detect(self, camera_index, t_s, image) -> list | None:
        """The detector's detections, or None while the light in view is changing (not judged)."""
        det = self.detectors[camera_index]
        light = self.light.check(camera_index, t_s)
        if light == "changing":
            return None
        if light == "settled":
            det.reset_background()
            self.clock.reset(camera_index, t_s)
        rate = det.segmenter.automatic_learning_rate(self.clock.frames_taken(camera_index, t_s))
        return det.process(image, rate)

    def on_frame(self, camera_index, t_s, image):
        detections = self.detect(camera_index, t_s, image)
        if detections and self.detectors[camera_index].is_target(detections):
            self.bank.trigger(self.ctx.camera_lamps[camera_index], t_s)
        return detections


class DetectorConfirmed(DetectorPerFrame):
    """k-of-n confirmation per track (the paper's eq. 12; its implementation switches on 2 of the last 6 frames)."""

    name = "detector_confirmed"
    tracking = True
    #: per track, a track must be seen in n frames before it confirms
    window_must_fill = True

    @classmethod
    def decisions(cls, spec) -> str:
        # per track it counts a frame's own decision while the track is plausible
        own = super().decisions(spec)
        return "plausible" if own == "track" and cls.window_must_fill else own

    def __init__(self, ctx):
        super().__init__(ctx)
        self.k = ctx.spec.k or PAPER_K
        self.n = ctx.spec.n or PAPER_N
        # per track, a track must be seen in n frames before it confirms (TrackWindows)
        full = self.window_must_fill and self.decides_per_track(ctx.spec) and windows_wait(ctx.sensors)
        self.windows = [TrackWindows(self.k, self.n, full_window=full) for _ in ctx.camera_lamps]

    def confirmed_tracks(self, camera_index, detections) -> set:
        """Record this frame's target decisions per track; the keys of the tracks now confirmed."""
        window = self.windows[camera_index]
        return window.update(self.marks(self.detectors[camera_index], detections, window))

    def marks(self, det, detections, window: TrackWindows) -> dict:
        """This frame's ``{track key: hit?}``: per frame, any target; per track, ``frame_hit``, young
        fragments counted for the established track they stand on."""
        return keyed_marks(detections, det.target_threshold, window)[1]

    def confirmed(self, camera_index, detections) -> bool:
        return bool(self.confirmed_tracks(camera_index, detections))

    def on_frame(self, camera_index, t_s, image):
        detections = self.detect(camera_index, t_s, image)
        if detections is not None and self.confirmed(camera_index, detections):
            self.bank.trigger(self.ctx.camera_lamps[camera_index], t_s)
        return detections


class DetectorTracked(DetectorConfirmed):
    """detector_confirmed deciding per track: k of n frames of one plausible target track."""

    name = "detector_tracked"
    tracking = True

    #: a target track is plausible by definition: no young-track wait
    window_must_fill = False

    def marks(self, det, detections, window: TrackWindows) -> dict:
        hits: dict = {}  # only frames of a track already judged a target count
        for d in detections:
            hits[d.track_id] = hits.get(d.track_id, False) or det.is_target([d])
        return hits


class DetectorNetwork(DetectorConfirmed):
    """Confirmed detections are messaged to the lamps ahead, so they are lit before the object arrives.

    Class-aware: a vehicle lights more lamps ahead than a pedestrian, held for its kind's hold_factor
    (config.kinds; a car's half as long). The direction of travel comes from the detection's ground
    position over the last frames; when it is unknown both neighbours are told. Notifications repeat
    every ``repeat_s`` while the object is seen.
    """

    name = "detector_network"

    def __init__(self, ctx):
        super().__init__(ctx)
        self.lamps_ahead = ctx.network.spec.neighbours_ahead.model_dump()
        self.repeat_s = ctx.network.spec.repeat_s
        self.last_sent_s = np.full(len(ctx.camera_lamps), -math.inf)
        self.last_x_m: list[dict[int, tuple[float, float]]] = [{} for _ in ctx.camera_lamps]

    def _direction(self, camera_index, t_s, det) -> int:
        """+1 / -1 along the street (s) from the track's ground velocity (or positions), 0 when not yet known."""
        line = self.ctx.street.centreline
        if det.velocity_x_mps is not None:
            vx = det.velocity_x_mps
            if not line.is_straight_x:  # the world velocity along the street where the camera looks
                vx = float(line.unrotate(self.ctx.street.lamps[self.ctx.camera_lamps[camera_index]].along_m,
                                         vx, det.velocity_y_mps or 0.0)[0])
            return 0 if abs(vx) < 0.3 else int(np.sign(vx))
        cam = self.ctx.street.cameras[camera_index].camera
        x, y, w, h = det.box_px
        ground = cam.pixel_to_ground(np.array([[x + w / 2 - 0.5, y + h - 0.5]]))[0]
        if not line.is_straight_x and np.isfinite(ground[0]):
            ground = np.array(line.to_sd(float(ground[0]), float(ground[1])))  # s, d
        if not np.isfinite(ground[0]) or det.track_id is None:
            return 0
        seen = self.last_x_m[camera_index]
        prev = seen.get(det.track_id)
        seen[det.track_id] = (t_s, float(ground[0]))
        if prev is None or t_s - prev[0] <= 0:
            return 0
        vx = (ground[0] - prev[1]) / (t_s - prev[0])
        return 0 if abs(vx) < 0.3 else int(np.sign(vx))

    def on_frame(self, camera_index, t_s, image):
        detections = self.detect(camera_index, t_s, image)
        if detections is None:
            return detections
        confirmed = self.confirmed_tracks(camera_index, detections)
        if not confirmed:
            return detections
        lamp_index = self.ctx.camera_lamps[camera_index]
        self.bank.trigger(lamp_index, t_s)
        det = self.detectors[camera_index]
        # the confirmed tracks' detections that are hits this frame (as their windows count them)
        targets = [d for d in detections
                   if d.track_id in confirmed and d.cls != "noise" and frame_hit(d, det.target_threshold)]
        if not targets or t_s - self.last_sent_s[camera_index] < self.repeat_s:
            if targets:
                # keep tracking directions between notifications
                for d in targets:
                    self._direction(camera_index, t_s, d)
            return detections
        best = max(targets, key=lambda d: self.lamps_ahead.get(detection_class(d), 1))
        direction = self._direction(camera_index, t_s, best)
        ahead = self.lamps_ahead.get(detection_class(best), 1)
        n = len(self.ctx.lamps)
        if direction == 0:
            receivers = [j for j in range(lamp_index - ahead, lamp_index + ahead + 1) if 0 <= j < n and j != lamp_index]
        else:
            receivers = [lamp_index + direction * k for k in range(1, ahead + 1) if 0 <= lamp_index + direction * k < n]
        if receivers:
            self.ctx.network.send(lamp_index, receivers, "light", {"cls": detection_class(best)})
            self.last_sent_s[camera_index] = t_s
        return detections

    def on_message(self, lamp_index, t_s, message):
        if message.kind == "light":
            kind = AGENT_KINDS.get(message.payload.get("cls", ""))  # a detector class: a kind's name
            factor = kind.hold_factor if kind is not None else 1.0
            self.bank.trigger(lamp_index, t_s, hold_s=self.ctx.hold_s * factor)
