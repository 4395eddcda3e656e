"""detector_located on the real suburban camera geometry: a target seen ahead lights the zone it is in."""

from pathlib import Path

import numpy as np

from citysim.config.scenario import ControllerSpec, load_scenario
from citysim.sim.loop import build_controller, deliver_messages
from citysim.sim.night import build_night
from detector.detector import Detection

REPO = Path(__file__).resolve().parents[3]


def target_detection(box_px, track_id: int = 7, **track) -> Detection:
    """A pedestrian detection whose track is a target (no ground fields: placed by its box)."""
    probabilities = np.array([0.05, 0.9, 0.02, 0.02, 0.01])
    return Detection(tuple(box_px), np.zeros(6), "pedestrian", probabilities, 0.95, track_id,
                     track_cls="pedestrian", track_p_target=0.93, track_target=True, **track)


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
    detection = target_detection(box)
    controller.place(k, 0.0, [detection])
    night.env.run(until=0.5)
    assert controller.ctx.network.stats.delivered == 0, "one frame of a track is not confirmed (2 of 6)"
    controller.place(k, 0.5, [detection])
    night.env.run(until=1.0)  # the radio's latency
    lamps = controller.ctx.lamps
    assert lamps[k + 1].target_level == 1.0, "the zone the walker stands in is lit, over the radio"
    assert controller.ctx.network.stats.delivered >= 1
    assert all(lamps[j].target_level < 1.0 for j in range(len(lamps)) if j not in (k, k + 1))


def test_a_track_that_is_not_a_target_lights_nothing_however_often_seen():
    scenario = load_scenario(REPO / "scenarios" / "suburban_night.yaml")
    night = build_night(scenario)
    controller = build_controller(night, ControllerSpec(name="detector_located"))
    insect = Detection((150, 150, 10, 30), np.zeros(6), "pedestrian", np.array([0.1, 0.8, 0.05, 0.03, 0.02]), 0.9, 3,
                       track_cls="noise", track_p_target=0.9, track_target=False, track_reason="erratic")
    for k in range(10):
        controller.place(2, k / 15, [insect])
    assert not controller.tracks and controller.ctx.network.stats.sent == 0
    assert all(lamp.target_level < 1.0 for lamp in controller.ctx.lamps)


def test_the_detectors_ground_velocity_is_used_when_the_track_has_one():
    scenario = load_scenario(REPO / "scenarios" / "suburban_night.yaml")
    night = build_night(scenario)
    controller = build_controller(night, ControllerSpec(name="detector_located"))
    car = target_detection((150, 150, 40, 30), track_id=9, ground_x_m=60.0, ground_y_m=3.0, velocity_x_mps=12.0,
                           velocity_y_mps=0.0, speed_mps=12.0)
    controller.place(1, 0.0, [car])
    controller.place(1, 0.1, [car])
    track = controller.tracks[(1, 9)]
    # two positions: too few for the controller's own fit (3 over 0.3 s); the detector's velocity is there
    assert track.vx_mps == 12.0 and track.last == (0.1, 60.0)
