"""Controllers: the ways of switching a chain of lamps, compared on the same traffic.

One small class per controller, chosen by name from ``CONTROLLERS``. A
controller owns one decision-maker per lamp and is fed by the simulation loop
(``citysim.sim.loop``): camera frames at the camera's frame rate (only if
``uses_camera``), agent snapshots at the physics rate (PIR needs them: it senses
heat, not pixels) and network messages. It decides by calling ``trigger`` (light
this lamp now and keep it lit for the hold time) or ``set_level``; the shared
``LampBank`` turns triggers into targets and releases lamps after the hold time.

Every camera controller sees the frames its own lamps' light produces: a lamp
that switches brightens its camera's scene, and the detector's background model
is rebuilt once the light settles (the paper's implementation does the same).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from citysim.config.kinds import AGENT_KINDS
from citysim.config.scenario import ControllerSpec, NeighboursAhead
from citysim.control.lamps import Lamp
from citysim.world.agents import AgentState
from citysim.world.street import Street
from detector.segment import Segmenter, SegmenterParams


@dataclass
class ControlContext:
    """What every controller may read: the street, the lamps and the network."""

    street: Street
    lamps: list[Lamp]
    hold_s: float
    dim_level: float
    frame_period_s: float
    rng: np.random.Generator
    network: object | None = None  # citysim.control.network.Network for networked controllers
    start_hour: float = 22.0
    spec: ControllerSpec = field(default_factory=lambda: ControllerSpec(name="always_on"))
    neighbours_ahead: NeighboursAhead = field(default_factory=NeighboursAhead)


class LampBank:
    """Lamps lit by triggers and released to dim after the hold time."""

    def __init__(self, ctx: ControlContext):
        self.ctx = ctx
        self.lit_until_s = np.full(len(ctx.lamps), -math.inf)
        self.first_trigger_s = np.full(len(ctx.lamps), math.nan)
        self.last_trigger_s = np.full(len(ctx.lamps), math.nan)
        self.triggers = np.zeros(len(ctx.lamps), dtype=np.int64)

    def trigger(self, lamp_index: int, t_s: float, hold_s: float | None = None) -> None:
        if self.triggers[lamp_index] == 0:
            self.first_trigger_s[lamp_index] = t_s
        self.last_trigger_s[lamp_index] = t_s
        self.triggers[lamp_index] += 1
        until = t_s + (self.ctx.hold_s if hold_s is None else hold_s)
        if until > self.lit_until_s[lamp_index]:
            self.lit_until_s[lamp_index] = until
        lamp = self.ctx.lamps[lamp_index]
        if lamp.target_level < 1.0:
            lamp.set_target(t_s, 1.0)

    def release_expired(self, t_s: float) -> None:
        """Called every physics step: lamps whose hold ran out go back to dim."""
        for i in np.flatnonzero(self.lit_until_s <= t_s):
            lamp = self.ctx.lamps[i]
            if lamp.target_level > self.ctx.dim_level:
                lamp.set_target(t_s, self.ctx.dim_level)


class Controller:
    """Base: a named way of switching the lamps. Subclasses override the hooks they need."""

    name: ClassVar[str] = ""
    uses_camera: ClassVar[bool] = False
    senses: ClassVar[bool] = True  # pays the sensing power (camera/board/IR or PIR)
    initial_level: ClassVar[str] = "dim"  # "dim" or "full"

    def __init__(self, ctx: ControlContext):
        self.ctx = ctx
        self.bank = LampBank(ctx)

    def on_physics_step(self, t_s: float, agents: Sequence[AgentState]) -> None:
        self.bank.release_expired(t_s)

    def on_frame(self, lamp_index: int, t_s: float, image: np.ndarray) -> list | None:
        """Handle one camera frame; return the detector's detections if there are any (for confusion metrics)."""
        return None

    def on_message(self, lamp_index: int, t_s: float, message) -> None:
        pass

    def motion_seen(self, lamp_index: int) -> bool:
        """Does this lamp's camera need every frame now? (see ``citysim.sim.loop.CameraSchedule``)

        True while its last judged frame held a moving region.
        """
        return False


class AlwaysOn(Controller):
    """Conventional lighting: every lamp at full level all night, no sensing."""

    name = "always_on"
    senses = False
    initial_level = "full"

    def on_physics_step(self, t_s, agents):
        pass


class Schedule(Controller):
    """Part-night dimming by the clock: the scenario's schedule steps (clock hour -> level).

    Without steps: full until midnight, dim from 00:00 to 05:00, full again after (a common
    part-night regime).
    """

    name = "schedule"
    senses = False
    initial_level = "full"

    def __init__(self, ctx):
        super().__init__(ctx)
        steps = [(s.start_hour, s.level) for s in ctx.spec.schedule]
        self.steps = sorted(steps) if steps else [(0.0, ctx.dim_level), (5.0, 1.0), (18.0, 1.0)]

    def level_at_hour(self, hour: float) -> float:
        """The step in force at a clock hour (the last step of the day wraps past midnight)."""
        level = self.steps[-1][1]
        for start, step_level in self.steps:
            if hour >= start:
                level = step_level
        return level

    def on_physics_step(self, t_s, agents):
        level = self.level_at_hour((self.ctx.start_hour + t_s / 3600.0) % 24.0)
        for lamp in self.ctx.lamps:
            if lamp.target_level != level:
                lamp.set_target(t_s, level)


#: PIR reference values: 12 m reach (the upper end of commercial sensors), a 110 deg cone, and a
#: 90% chance per second of seeing a warm body inside it.
PIR_RANGE_M = 12.0
PIR_CONE_DEG = 110.0
PIR_DETECTION_PROBABILITY_PER_S = 0.9


class PassiveInfrared(Controller):
    """A PIR sensor per pole: warm bodies within range in its cone, with a detection probability; no classes.

    Reference values: commercial PIR reaches 3-12 m in a 110-120 deg cone and needs a few degrees of
    thermal contrast; it cannot tell a fox from a pedestrian.
    """

    name = "pir"

    def __init__(self, ctx):
        super().__init__(ctx)
        self.range_m = PIR_RANGE_M
        self.cone_deg = PIR_CONE_DEG
        self.p_detect_per_s = PIR_DETECTION_PROBABILITY_PER_S
        self.period_s = 0.25  # the sensor's output is sampled at 4 Hz
        self.next_sample_s = 0.0
        cams = [lamp.camera for lamp in ctx.street.lamps]
        self.pole_xy_m = np.array([[c.x_m, c.y_m] for c in cams])
        self.heading = np.array([c.heading_unit for c in cams])

    def on_physics_step(self, t_s, agents):
        super().on_physics_step(t_s, agents)
        if t_s < self.next_sample_s or not agents:
            return
        self.next_sample_s = t_s + self.period_s
        xy = np.array([[a.x_m, a.y_m] for a in agents])
        rel = xy[None, :, :] - self.pole_xy_m[:, None, :]  # lamps x agents x 2
        dist = np.linalg.norm(rel, axis=2)
        cos_angle = np.einsum("lak,lk->la", rel, self.heading) / np.maximum(dist, 1e-9)
        in_cone = (dist <= self.range_m) & (cos_angle >= math.cos(math.radians(self.cone_deg / 2)))
        p = 1.0 - (1.0 - self.p_detect_per_s) ** self.period_s
        seen = in_cone & (self.ctx.rng.random(in_cone.shape) < p)
        for lamp_index in np.flatnonzero(seen.any(axis=1)):
            self.bank.trigger(int(lamp_index), t_s)


class BackgroundClock:
    """Frames each lamp camera has *taken* since its background model was (re)built.

    The simulator judges an idle camera only now and then (``citysim.sim.loop.CameraSchedule``), but
    the camera takes every frame. MOG2's automatic learning rate, 1 / min(2 n, history), counts
    frames fed; fed one frame a second, a young model would learn 15 times too fast and swallow a
    car coming head-on. So each judged frame is fed at the rate of the frames taken.
    """

    def __init__(self, n_lamps: int, fps: float):
        self.fps = fps
        self.reset_at_s = [0.0] * n_lamps

    def reset(self, lamp_index: int, t_s: float) -> None:
        self.reset_at_s[lamp_index] = t_s

    def frames_taken(self, lamp_index: int, t_s: float) -> int:
        return int(round((t_s - self.reset_at_s[lamp_index]) * self.fps))


class ForegroundThreshold(Controller):
    """The paper's naive baseline: light when a foreground contour exceeds a fraction of the frame.

    Section 7: 'the object is considered to be detected, when the size of its contour area exceeds a
    pre-defined threshold' - 5% caught 20% of targets, 0.5% switched on falsely 90% of the time.
    """

    uses_camera = True
    fraction = 0.05

    def __init__(self, ctx):
        super().__init__(ctx)
        if ctx.spec.threshold_fraction is not None:
            self.fraction = ctx.spec.threshold_fraction
        self.segmenters = [Segmenter(SegmenterParams()) for _ in ctx.lamps]
        self.light = LightChangeWatch(ctx)
        self.last_counts = [0] * len(ctx.lamps)
        self.clock = BackgroundClock(len(ctx.lamps), 1.0 / ctx.frame_period_s)

    def motion_seen(self, lamp_index):
        return self.last_counts[lamp_index] > 0

    def on_frame(self, lamp_index, t_s, image):
        seg = self.segmenters[lamp_index]
        light = self.light.check(lamp_index, t_s)
        if light == "changing":
            return None
        if light == "settled":
            seg.reset()
            self.clock.reset(lamp_index, t_s)
        rate = seg.automatic_learning_rate(self.clock.frames_taken(lamp_index, t_s))
        regions = seg.apply(image, rate)
        self.last_counts[lamp_index] = len(regions)
        n_px = image.shape[0] * image.shape[1]
        if len(regions.areas_px) and regions.areas_px.max() > self.fraction * n_px:
            self.bank.trigger(lamp_index, t_s)
        return None


class Threshold5(ForegroundThreshold):
    name = "threshold_5"
    fraction = 0.05


class Threshold05(ForegroundThreshold):
    name = "threshold_05"
    fraction = 0.005


class LightChangeWatch:
    """Tells a camera's background model when the lighting it sees changes and settles.

    The lamps that light a camera's view are its own and its neighbours'. While any of them ramps,
    MOG2 sees the whole scene change, so frames are not judged (a lamp would otherwise keep itself
    lit: switching makes foreground, foreground switches). Once the light is steady the background
    model is rebuilt, as the paper's implementation does.
    """

    def __init__(self, ctx: ControlContext, neighbours: int = 1):
        self.ctx = ctx
        n = len(ctx.lamps)
        self.watched = [list(range(max(0, i - neighbours), min(n, i + neighbours + 1))) for i in range(n)]
        self.was_changing = [False] * n

    def check(self, lamp_index: int, t_s: float) -> str:
        """'changing' (skip this frame), 'settled' (rebuild the background, then judge) or 'steady'."""
        changing = any(self.ctx.lamps[j].is_ramping(t_s) for j in self.watched[lamp_index])
        was = self.was_changing[lamp_index]
        self.was_changing[lamp_index] = changing
        if changing:
            return "changing"
        return "settled" if was else "steady"


class DetectorPerFrame(Controller):
    """The paper's detector, deciding per frame on the target group."""

    name = "detector"
    uses_camera = True

    def __init__(self, ctx):
        super().__init__(ctx)
        from detector.classifier import default_model
        from detector.detector import Detector

        model = default_model()
        threshold = 0.5 if ctx.spec.target_threshold is None else ctx.spec.target_threshold
        self.detectors = [Detector(site.camera, model=model, target_threshold=threshold) for site in ctx.street.lamps]
        self.light = LightChangeWatch(ctx)
        self.clock = BackgroundClock(len(ctx.lamps), 1.0 / ctx.frame_period_s)

    def motion_seen(self, lamp_index):
        return len(self.detectors[lamp_index].last_regions) > 0

    def detect(self, lamp_index, t_s, image) -> list | None:
        """The detector's detections, or None while the light in view is changing (not judged)."""
        det = self.detectors[lamp_index]
        light = self.light.check(lamp_index, t_s)
        if light == "changing":
            return None
        if light == "settled":
            det.reset_background()
            self.clock.reset(lamp_index, t_s)
        rate = det.segmenter.automatic_learning_rate(self.clock.frames_taken(lamp_index, t_s))
        return det.process(image, rate)

    def on_frame(self, lamp_index, t_s, image):
        detections = self.detect(lamp_index, t_s, image)
        if detections and self.detectors[lamp_index].is_target(detections):
            self.bank.trigger(lamp_index, t_s)
        return detections


class DetectorConfirmed(DetectorPerFrame):
    """k-of-n confirmation (the paper's eq. 12; its implementation switches on 2 of the last 6 frames)."""

    name = "detector_confirmed"

    def __init__(self, ctx):
        super().__init__(ctx)
        # the paper's implementation switches when 2 of the last 6 frames hold a target
        self.k = ctx.spec.k or 2
        self.n = ctx.spec.n or 6
        self.history = [deque(maxlen=self.n) for _ in ctx.lamps]

    def confirmed(self, lamp_index, detections) -> bool:
        hist = self.history[lamp_index]
        hist.append(self.detectors[lamp_index].is_target(detections))
        return sum(hist) >= self.k

    def on_frame(self, lamp_index, t_s, image):
        detections = self.detect(lamp_index, t_s, image)
        if detections is not None and self.confirmed(lamp_index, detections):
            self.bank.trigger(lamp_index, t_s)
        return detections


class DetectorNetwork(DetectorConfirmed):
    """Confirmed detections are messaged to the lamps ahead, so they are lit before the object arrives.

    Class-aware: a vehicle lights more lamps ahead than a pedestrian, each held for its kind's
    hold_factor (config.kinds: a car's half as long). Direction of travel: from the detection's ground
    position over the last frames; unknown, both neighbours are told. Repeats every ``repeat_s``.
    """

    name = "detector_network"

    def __init__(self, ctx):
        super().__init__(ctx)
        self.lamps_ahead = ctx.neighbours_ahead.model_dump()
        self.repeat_s = float(getattr(getattr(ctx.network, "spec", None), "repeat_s", 3.0))
        self.last_sent_s = np.full(len(ctx.lamps), -math.inf)
        self.last_x_m: list[dict[int, tuple[float, float]]] = [{} for _ in ctx.lamps]

    def _direction(self, lamp_index, t_s, det) -> int:
        """+1 / -1 along x from the track's ground positions, 0 when not yet known."""
        cam = self.ctx.street.lamps[lamp_index].camera
        x, y, w, h = det.box_px
        ground = cam.pixel_to_ground(np.array([[x + w / 2 - 0.5, y + h - 0.5]]))[0]
        if not np.isfinite(ground[0]) or det.track_id is None:
            return 0
        seen = self.last_x_m[lamp_index]
        prev = seen.get(det.track_id)
        seen[det.track_id] = (t_s, float(ground[0]))
        if prev is None or t_s - prev[0] <= 0:
            return 0
        vx = (ground[0] - prev[1]) / (t_s - prev[0])
        return 0 if abs(vx) < 0.3 else int(np.sign(vx))

    def on_frame(self, lamp_index, t_s, image):
        detections = self.detect(lamp_index, t_s, image)
        if detections is None or not self.confirmed(lamp_index, detections):
            return detections
        self.bank.trigger(lamp_index, t_s)
        targets = [d for d in detections if d.cls != "noise" and d.p_target >= self.detectors[lamp_index].target_threshold]
        if not targets or self.ctx.network is None or t_s - self.last_sent_s[lamp_index] < self.repeat_s:
            if targets:
                # keep tracking directions between notifications
                for d in targets:
                    self._direction(lamp_index, t_s, d)
            return detections
        best = max(targets, key=lambda d: self.lamps_ahead.get(d.cls, 1))
        direction = self._direction(lamp_index, t_s, best)
        ahead = self.lamps_ahead.get(best.cls, 1)
        n = len(self.ctx.lamps)
        if direction == 0:
            receivers = [j for j in range(lamp_index - ahead, lamp_index + ahead + 1) if 0 <= j < n and j != lamp_index]
        else:
            receivers = [lamp_index + direction * k for k in range(1, ahead + 1) if 0 <= lamp_index + direction * k < n]
        if receivers:
            self.ctx.network.send(lamp_index, receivers, "light", {"cls": best.cls})
            self.last_sent_s[lamp_index] = t_s
        return detections

    def on_message(self, lamp_index, t_s, message):
        if message.kind == "light":
            kind = AGENT_KINDS.get(message.payload.get("cls", ""))  # a detector class: a kind's name
            factor = kind.hold_factor if kind is not None else 1.0
            self.bank.trigger(lamp_index, t_s, hold_s=self.ctx.hold_s * factor)


#: Controllers by name: the scenario's ``controllers`` list and ``--controllers`` pick from these.
CONTROLLERS: dict[str, type[Controller]] = {
    cls.name: cls
    for cls in (AlwaysOn, Schedule, PassiveInfrared, Threshold5, Threshold05, DetectorPerFrame, DetectorConfirmed, DetectorNetwork)
}
