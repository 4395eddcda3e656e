"""What every camera controller needs, and the paper's naive baseline built on it.

Every camera controller sees the frames its own lamps' light produces: a lamp that switches
brightens its camera's scene, so frames are not judged while the light in view changes, and the
background model is rebuilt once it settles (the paper's implementation does the same).
``ForegroundThreshold`` is the paper's section 7 baseline: light when a foreground region
covers a share of the frame.
"""

from __future__ import annotations

from citysim.control.base import ControlContext, Controller
from detector.segment import Segmenter, SegmenterParams


class BackgroundClock:
    """Frames each camera has *taken* since its background model was (re)built (by camera index).

    The simulator judges an idle camera only now and then (``citysim.sim.cameras.CameraSchedule``), but
    the camera takes every frame. MOG2's automatic learning rate, 1 / min(2 n, history), counts
    frames fed; fed one frame a second, a young model would learn 15 times too fast and swallow a
    car coming head-on. So each judged frame is fed at the rate of the frames taken.
    """

    def __init__(self, n_cameras: int, fps: float):
        self.fps = fps
        self.reset_at_s = [0.0] * n_cameras

    def reset(self, camera_index: int, t_s: float) -> None:
        self.reset_at_s[camera_index] = t_s

    def frames_taken(self, camera_index: int, t_s: float) -> int:
        return int(round((t_s - self.reset_at_s[camera_index]) * self.fps))


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
        # the whole frame, as the paper's baseline; the background forgets at the camera's own rate
        if ctx.sensors is not None:  # fast mode: a calibrated per-frame trigger model, same interface
            self.segmenters = ctx.sensors.segmenters(ctx)
        else:
            self.segmenters = [Segmenter(SegmenterParams(), fps=1.0 / ctx.frame_period_s) for _ in ctx.camera_lamps]
        self.light = LightChangeWatch(ctx)
        self.last_counts = [0] * len(ctx.camera_lamps)
        self.clock = BackgroundClock(len(ctx.camera_lamps), 1.0 / ctx.frame_period_s)

    def motion_seen(self, camera_index):
        return self.last_counts[camera_index] > 0

    def on_frame(self, camera_index, t_s, image):
        seg = self.segmenters[camera_index]
        light = self.light.check(camera_index, t_s)
        if light == "changing":
            return None
        if light == "settled":
            seg.reset()
            self.clock.reset(camera_index, t_s)
        rate = seg.automatic_learning_rate(self.clock.frames_taken(camera_index, t_s))
        regions = seg.apply(image, rate)
        self.last_counts[camera_index] = len(regions)
        n_px = image.shape[0] * image.shape[1]
        if len(regions.areas_px) and regions.areas_px.max() > self.fraction * n_px:
            self.bank.trigger(self.ctx.camera_lamps[camera_index], t_s)
        return None


class Threshold5(ForegroundThreshold):
    name = "threshold_5"
    fraction = 0.05


class Threshold05(ForegroundThreshold):
    name = "threshold_05"
    fraction = 0.005


class LightChangeWatch:
    """Tells a camera's background model when the lighting it sees changes and settles.

    The lamps that light a camera's view are its pole's and the neighbours'. While any of them ramps,
    MOG2 sees the whole scene change, so frames are not judged (a lamp would otherwise keep itself
    lit: switching makes foreground, foreground switches). Once the light is steady the background
    model is rebuilt, as the paper's implementation does.
    """

    def __init__(self, ctx: ControlContext, neighbours: int = 1):
        self.ctx = ctx
        n = len(ctx.lamps)
        self.watched = [list(range(max(0, i - neighbours), min(n, i + neighbours + 1))) for i in ctx.camera_lamps]
        self.was_changing = [False] * len(ctx.camera_lamps)

    def check(self, camera_index: int, t_s: float) -> str:
        """'changing' (skip this frame), 'settled' (rebuild the background, then judge) or 'steady'."""
        states = self.ctx.lamp_states
        # most frames no lamp ramps: then none of the watched ones does
        changing = states.any_ramping(t_s) and any(states.ramping(t_s)[j] for j in self.watched[camera_index])
        was = self.was_changing[camera_index]
        self.was_changing[camera_index] = changing
        if changing:
            return "changing"
        return "settled" if was else "steady"
