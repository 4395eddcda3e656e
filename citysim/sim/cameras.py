"""The lamp cameras of a run: which are judged each frame, and the process that films them.

Every camera takes frames at its frame rate; ``CameraSchedule`` picks the ones worth judging
(anything in view, light changing, motion in the last judged frame) and judges the rest
sparsely. ``film`` is the simpy process: it renders each chosen camera's frame, hands it to the
controller and tells the collectors what was seen and what the detector said.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from citysim.control.lamps import Lamp
from citysim.metrics.collector import Collector
from citysim.sim.frames import CameraFrames
from citysim.world.street import Street


class CameraSchedule:
    """Which cameras (``Street.cameras``, by camera index) are judged this frame: every one that may see something, the rest sparsely.

    A camera is *busy* when an agent stands in its view (projected inside the frame, with a margin
    for what is about to enter), when the light in its view is changing, or when its last judged
    frame held a moving region (an insect, a swaying branch, an animal: it stays at full rate while
    that lasts). An idle camera looks at a static scene; it is judged every ``idle_stride``-th frame,
    which keeps its background model fed (at the learning rate of every frame taken, see
    ``citysim.control`` BackgroundClock) and samples the noise that would wake it. With
    ``idle_stride`` 1 every frame of every camera is judged (exact, and slow).
    """

    MARGIN = 0.25  # fraction of the frame size an agent may stand outside it and still count as in view
    # the detector ignores what is beyond 25 m; 15 m more wakes a camera ~1 s before a car at
    # 60 km/h comes into its range, so nothing in range is ever judged at the idle rate
    MAX_FORWARD_M = 40.0

    def __init__(self, street: Street, idle_stride: int):
        self.cameras = [site.camera for site in street.cameras]
        self.idle_stride = idle_stride
        self.n = len(self.cameras)
        n_lamps = len(street.lamps)
        # the lamps lighting each camera's view: its pole's and the neighbours'
        self.watch = [list(range(max(0, c.lamp - 1), min(n_lamps, c.lamp + 2))) for c in street.cameras]
        self._poles_m = np.array([cam.position_m[:2] for cam in self.cameras]).reshape(-1, 2)
        self._headings = np.array([cam.heading_unit for cam in self.cameras]).reshape(-1, 2)

    def in_view(self, agents) -> np.ndarray:
        busy = np.zeros(self.n, dtype=bool)
        if not agents:
            return busy
        pts = np.array([[a.x_m, a.y_m, 0.9] for a in agents])
        # every camera at once, to pass over those with nobody ahead within range; the decision
        # is the per-camera sum below (this one may differ from it in the last bits, hence the
        # millimetre of slack)
        ahead_m = np.einsum("cj,acj->ac", self._headings, pts[:, None, :2] - self._poles_m[None])
        maybe = ((ahead_m > -1e-3) & (ahead_m < self.MAX_FORWARD_M + 1e-3)).any(axis=0)
        for i in np.flatnonzero(maybe).tolist():
            cam = self.cameras[i]
            fwd = cam.forward_and_lateral_m(pts)[:, 0]
            near = (fwd > 0.0) & (fwd < self.MAX_FORWARD_M)
            if not near.any():
                continue
            px = cam.project(pts[near], distort=False)
            mu, mv = self.MARGIN * cam.width_px, self.MARGIN * cam.height_px
            inside = (px[:, 0] > -mu) & (px[:, 0] < cam.width_px + mu) & (px[:, 1] > -mv) & (px[:, 1] < cam.height_px + mv)
            busy[i] = bool(inside.any())
        return busy

    def active(self, k: int, t_s: float, agents, lamps: list[Lamp], controller) -> np.ndarray:
        if self.idle_stride <= 1 or k % self.idle_stride == 0:
            return np.ones(self.n, dtype=bool)
        busy = self.in_view(agents)
        for i in range(self.n):
            if not busy[i]:
                busy[i] = controller.motion_seen(i) or any(lamps[j].is_ramping(t_s) for j in self.watch[i])
        return busy


def film(night, frames: CameraFrames, controller, lamps: Sequence[Lamp], collectors: Sequence[Collector]):
    """simpy process: every camera frame at the cameras' frame rate, judged where scheduled.

    Frames are taken at k / fps; a frame shows the agents of the latest physics step, rendered by
    ``frames`` (or handed over by it, when controllers in step share them). The controller and the
    collectors get the camera index (``Street.cameras``; camera i is lamp i's own).
    """
    env = night.env
    fps = night.street.lamps[0].camera.fps
    schedule = CameraSchedule(night.street, night.scenario.simulation.idle_frame_stride)
    k = 0
    while True:
        yield env.timeout(max(0.0, k / fps - env.now))
        t = env.now
        levels = controller.ctx.lamp_states.levels_at(t)
        agents = night.street.in_world(night.agents)  # the cameras look at the world
        for i in np.flatnonzero(schedule.active(k, t, agents, lamps, controller)):
            frame = frames.frame(int(i), k, t, agents, levels)
            detections = controller.on_frame(int(i), t, frame.image)
            for collector in collectors:
                collector.on_frame(int(i), t, frame.truth, detections)
        k += 1
