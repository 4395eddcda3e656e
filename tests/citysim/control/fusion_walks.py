"""A walker (or a ghost) as the street's cameras would report it: real camera models, synthetic boxes.

Each frame every camera is judged; a camera in whose view the walker stands reports it with
probability ``p_detect`` as a detection whose box stands on the walker's ground point (projected
with the camera model, so the fusion's pixel-to-ground path and covariance are the real ones).
"""

from __future__ import annotations

import numpy as np

from citysim.config.scenario import scenario_from_mapping
from citysim.control.camera_rays import CameraRays
from citysim.control.fusion.births import BirthMap
from citysim.control.fusion.measurement import measure
from citysim.control.fusion.street_frame import StreetFrame
from citysim.control.fusion.tracker import StreetTracker
from citysim.control.fusion.views import CameraViews
from citysim.world.street import build_street
from detector.detector import Detection
from tests.citysim.fast.synthetic import tiny_scenario

FPS = 15.0


def street(two_way: bool = False):
    """Three lamps 30 m apart (poles at x = 15, 45, 75 m) on a 90 m street, forward cameras and,
    with ``two_way``, backward ones."""
    mapping = tiny_scenario()
    if two_way:
        mapping["lamps"]["camera"]["back_heading_deg"] = 188
    return build_street(scenario_from_mapping(mapping))


class Rig:
    """A street tracker and the cameras that feed it."""

    def __init__(self, two_way: bool = False):
        self.street = street(two_way)
        self.frame = StreetFrame.of(self.street)
        cameras = [site.camera for site in self.street.cameras]
        self.rays = [CameraRays(c) for c in cameras]
        self.views = CameraViews(cameras, self.frame)
        lateral = [lane.y_center_m for lane in self.street.lanes] + [w.y_center_m for w in self.street.sidewalks]
        self.tracker = StreetTracker(self.frame, self.views, BirthMap(self.views, self.street.length_m, lateral))

    def detection(self, camera: int, s_m: float, d_m: float, track_id: int) -> Detection:
        """A pedestrian detection of camera ``camera`` standing at street (s, d)."""
        x_m, y_m = self.frame.to_ground(s_m, d_m)
        (u0, v0), (_, v1) = self.rays[camera].project_px(np.array([[x_m, y_m, 0.0], [x_m, y_m, 1.7]]))
        h = v0 - v1
        box = (int(round(u0 - h / 6)), int(round(v0 - h)), max(2, int(round(h / 3))), int(round(h)))
        return Detection(box, np.zeros(6), "pedestrian", np.zeros(5), 0.9, track_id)

    def step(self, t_s: float, where: tuple[float, float] | None, rng: np.random.Generator,
             p_detect: float = 0.8, track_id: int = 1) -> list[int]:  # fmt: skip
        """One frame of every camera at ``t_s``, the walker at street ``where`` (None: nobody); the
        ids of the street tracks its measurements went to."""
        fed = []
        for camera in range(self.views.n):
            measurements = []
            if where is not None and self.views.seen_sd(*where)[camera] and rng.random() < p_detect:
                noisy = (where[0] + rng.normal(0.0, 0.3), where[1] + rng.normal(0.0, 0.2))
                m = measure(self.frame, self.rays[camera], camera, self.detection(camera, *noisy, track_id), "pedestrian")
                measurements.append(m)
            self.tracker.observe(camera, t_s, measurements)
            if measurements:
                fed += [t.id for t in self.tracker.tracks if t.last_seen_s == t_s]
        return fed
