"""detector_located on the real suburban camera geometry: a target seen ahead lights the zone it is in."""

from pathlib import Path

import numpy as np

from citysim.config.scenario import ControllerSpec, load_scenario
from citysim.sim.loop import build_controller, deliver_messages
from citysim.sim.night import build_night
from detector.detector import Detection

REPO = Path(__file__).resolve().parents[3]


def confirmed_detection(controller, lamp: int, box_px, frames: int = 6) -> Detection:
    """A target detection whose track the camera's real tracker has confirmed (k of n frames)."""
    tracker = controller.detectors[lamp].tracker
    for _ in range(frames):
        (track_id,) = tracker.update(np.array([box_px], dtype=np.float64), np.array([True]))
    assert tracker.is_confirmed(int(track_id))
    probabilities = np.array([0.05, 0.9, 0.02, 0.02, 0.01])
    return Detection(tuple(box_px), np.zeros(6), "pedestrian", probabilities, 0.95, int(track_id))


def test_a_walker_20_m_ahead_of_camera_k_lights_lamp_k_plus_1():
    scenario = load_scenario(REPO / "scenarios" / "suburban_night.yaml")
    night = build_night(scenario)
    controller = build_controller(night, ControllerSpec(name="detector_located"))
    for i in range(night.n_lamps):
        night.env.process(deliver_messages(night, controller, i))
    k = 3
    cam = night.street.lamps[k].camera
    ahead = cam.position_m[:2] + 20.0 * cam.heading_unit  # 20 m ahead of the pole, on the ground
    x_m = float(ahead[0])
    zone = next(j for j, s in enumerate(night.street.lamps) if s.zone_start_m <= x_m < s.zone_end_m)
    assert zone == k + 1  # the geometry the issue names: what camera k sees stands in lamp k+1's zone
    # a walker-sized box standing there: feet at the projected ground point, 1.7 m tall
    feet, head = cam.project(np.array([[*ahead, 0.0], [*ahead, 1.7]]), distort=False)
    h = int(round(feet[1] - head[1]))
    box = (int(round(feet[0])) - 4, int(round(feet[1])) - h + 1, 8, h)
    detection = confirmed_detection(controller, k, box)

    controller.place(k, 0.0, [detection])
    night.env.run(until=0.5)  # the radio's latency
    lamps = controller.ctx.lamps
    assert lamps[k + 1].target_level == 1.0, "the zone the walker stands in is lit, over the radio"
    assert controller.ctx.network.stats.delivered >= 1
    assert all(lamps[j].target_level < 1.0 for j in range(len(lamps)) if j not in (k, k + 1))
