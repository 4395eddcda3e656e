"""Calibration records: detections near a candidate on the ground are its, not false alarms."""

from __future__ import annotations

import numpy as np
import pytest

from citysim.config.kinds import DETECTOR_CLASSES
from citysim.config.scenario import scenario_from_mapping
from citysim.fast.geometry import BEAM_AHEAD_M, CameraGeometry, LevelChanges, beam_id
from citysim.fast.records import CalibrationRecorder, RecordingSensors
from citysim.world.agents import AgentState
from citysim.world.street import build_street
from detector.detector import Detection
from tests.citysim.fast.synthetic import tiny_scenario


def agent(object_id: int, x_m: float, y_m: float, cls: str = "pedestrian", light_on: bool = False) -> AgentState:
    return AgentState(object_id, cls, x_m, y_m, 0.0, 1.4, 0.5, 0.5, 1.75, light_on=light_on)


def detection_at(cam, x_m: float, y_m: float) -> Detection:
    u, v = cam.project(np.array([[x_m, y_m, 0.0]]))[0]
    box = (int(round(u)) - 5, int(round(v)) - 30, 10, 30)
    return Detection(box, np.array([0, 0, 0, 10.0, 0, 0]), "pedestrian", np.array([0.1, 0.9, 0, 0, 0]), 0.9, 1)


def recorder_at_first_camera():
    """A calibration recorder on the tiny street, its first camera, and that camera's x, m."""
    geometry = CameraGeometry(build_street(scenario_from_mapping(tiny_scenario())))
    cam = geometry.cameras[0]
    return geometry, CalibrationRecorder(geometry, RecordingSensors(), 30.0), cam, float(cam.position_m[0])


def test_a_detection_on_the_ground_near_a_candidate_is_its_hit():
    geometry, recorder, cam, x0 = recorder_at_first_camera()
    walker, car = agent(1, x0 + 12.0, -4.3), agent(2, x0 + 25.0, -1.6, "vehicle", light_on=True)
    recorder.on_step(0.0, [walker, car], np.full(3, 0.2))
    idx = np.flatnonzero(geometry.candidates([walker, car]).seen[:, 0])
    assert set(idx.tolist()) == {0, 1}
    near_walker = detection_at(cam, x0 + 13.5, -4.3)  # 1.5 m from the walker
    beam = detection_at(cam, x0 + 10.0, 1.6)  # the car's beam, 15 m ahead of it
    stray = detection_at(cam, x0 + 12.0, 4.3)  # 8.6 m across from the walker, no light there
    hits: dict[int, int] = {}
    ahead: dict[int, float] = {}
    left = recorder._near_candidates(0, idx, hits, [near_walker, beam, stray], ahead)
    assert set(hits) == {1, 2} and left == [stray]
    # where each hit stands along its road user's heading (+x here), m: fast mode puts hits there
    assert ahead[1] == pytest.approx(1.5, abs=0.3) and ahead[2] == pytest.approx(-15.0, abs=0.5)


def test_boxes_projected_together_equal_boxes_projected_one_by_one():
    # fast mode projects a camera's candidates in one call; a box must not depend on its company
    geometry, _, cam, x0 = recorder_at_first_camera()
    agents = [agent(1, x0 + 6.0, -4.3), agent(2, x0 + 25.0, -1.6, "vehicle"), agent(3, x0 - 3.0, 1.0),
              agent(4, x0 + 14.0, 2.2, "cyclist")]  # fmt: skip
    together = geometry.boxes_px(0, agents)
    assert together == [geometry.boxes_px(0, [a])[0] for a in agents]
    assert together[2] == (0, 0, 1, 1)  # behind the camera: no box
    # the walker's box stands on its footprint: its bottom centre projects back near the feet
    x, y, w, h = together[0]
    u, v = cam.project(np.array([[x0 + 6.0, -4.3, 0.0]]))[0]
    assert abs(x + w / 2 - u) <= 1.0 and abs(y + h - v) <= 1.0


def test_a_beam_of_a_car_out_of_view_is_no_false_alarm_but_a_dark_spot_is():
    geometry, recorder, cam, x0 = recorder_at_first_camera()
    behind = agent(2, x0 - 6.0, -1.6, "vehicle", light_on=True)  # behind the camera, headlights on
    unlit = agent(3, x0 - 6.0, 1.6, "vehicle", light_on=False)
    recorder.on_step(0.0, [behind, unlit], np.full(3, 0.2))
    idx = np.flatnonzero(geometry.candidates([behind, unlit]).seen[:, 0])
    assert len(idx) == 0  # neither car is the camera's candidate
    beam = detection_at(cam, x0 + 10.0, -1.6)  # 16 m ahead of the lit car
    stray = detection_at(cam, x0 + 18.0, 4.3)  # 24 m from either car
    hits: dict[int, int] = {}
    assert recorder._near_candidates(0, idx, hits, [beam, stray]) == [stray]
    assert hits == {beam_id(2): DETECTOR_CLASSES.index("pedestrian")}  # the lit car's beam candidate's hit
    recorder.on_step(0.1, [unlit], np.full(3, 0.2))  # without headlights the same spot is a false alarm
    assert recorder._near_candidates(0, idx, {}, [beam, stray]) == [beam, stray]


def test_a_lit_road_user_behind_the_camera_is_a_beam_candidate_standing_where_its_light_is():
    geometry, _, cam, x0 = recorder_at_first_camera()
    # just behind the pole (the camera looks 8 degrees off the street's +x, across to the far lane)
    lit, unlit = agent(1, x0 - 2.0, -1.6, "vehicle", light_on=True), agent(2, x0 - 2.0, -1.6, "vehicle")
    far_back = agent(3, x0 - 40.0, -1.6, "vehicle", light_on=True)  # its light ends before the view
    cand = geometry.candidates([lit, unlit, far_back])
    assert not cand.seen[:, 0].any()
    assert cand.beam_seen[:, 0].tolist() == [True, False, False]
    assert cand.beam_forward_m[0, 0] == pytest.approx(cand.forward_m[0, 0] + BEAM_AHEAD_M, abs=0.2)
    x, y, w, h = geometry.beam_box_px(0, lit)  # stands on the beam's middle, 10 m ahead of the car
    u, v = cam.project(np.array([[x0 - 2.0 + BEAM_AHEAD_M, -1.6, 0.0]]))[0]
    assert abs(x + w / 2 - u) <= 1.0 and abs(y + h - v) <= 1.0
    seen_car = geometry.candidates([agent(4, x0 + 12.0, -1.6, "vehicle", light_on=True)])
    assert seen_car.seen[0, 0] and not seen_car.beam_seen[0, 0]  # a candidate's light is its own


def test_a_camera_watches_when_the_far_lamps_ahead_of_it_beyond_its_neighbours_change():
    # three lamps 30 m apart, every camera looking along +x: only the first sees a lamp 2 poles ahead
    geometry = CameraGeometry(build_street(scenario_from_mapping(tiny_scenario())))
    assert [far.tolist() for far in geometry.far_lamps] == [[2], [], []]
    changes = LevelChanges(geometry)
    changes.update(0.0, np.array([0.2, 0.2, 0.2]))
    assert changes.far_change_age_s(0, 5.0) == np.inf  # never seen to change
    changes.update(10.0, np.array([1.0, 1.0, 0.2]))  # its own and its neighbour's do not count
    assert changes.far_change_age_s(0, 12.0) == np.inf
    changes.update(20.0, np.array([1.0, 1.0, 0.6]))
    assert changes.far_change_age_s(0, 23.5) == pytest.approx(3.5)
    assert changes.far_change_age_s(2, 23.5) == np.inf  # nothing ahead of the last camera
