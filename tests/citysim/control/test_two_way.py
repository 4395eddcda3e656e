"""Two cameras per pole (suburban_night_two_way): each camera belongs to its pole's lamp, and what the
backward camera sees is placed with its own pose and lights the zone it stands in."""

from pathlib import Path

import numpy as np
import pytest

from citysim.config.base import FieldPathError
from citysim.config.scenario import ControllerSpec, ScenarioError, load_scenario, override
from citysim.control.track_windows import PAPER_N
from citysim.sim.cameras import CameraSchedule
from citysim.sim.loop import build_controller, deliver_messages, run_controller
from citysim.sim.night import build_night
from citysim.world.agents import AgentState
from tests.citysim.control.test_located import target_detection

REPO = Path(__file__).resolve().parents[3]
TWO_WAY = REPO / "scenarios" / "suburban_night_two_way.yaml"


def walker_box(cam, ground_xy) -> tuple[int, int, int, int]:
    """A walker-sized box (feet at the projected ground point, 1.7 m tall) in ``cam``'s image, px."""
    feet, head = cam.project(np.array([[*ground_xy, 0.0], [*ground_xy, 1.7]]), distort=False)
    h = int(round(feet[1] - head[1]))
    return (int(round(feet[0])) - 4, int(round(feet[1])) - h + 1, 8, h)


def test_every_pole_carries_a_forward_and_a_backward_camera_numbered_after_the_lamps():
    street = build_night(load_scenario(TWO_WAY)).street
    n = len(street.lamps)
    cams = street.cameras
    assert len(cams) == 2 * n and street.camera_lamps == tuple(range(n)) * 2
    for k in range(n):
        own, back = cams[k].camera, cams[n + k].camera
        assert own == street.lamps[k].camera  # camera k is still lamp k's own, as with one camera per pole
        assert (back.x_m, back.y_m) == (own.x_m, own.y_m) == (street.lamps[k].x_m, street.lamps[k].y_m)
        assert back.yaw_deg == 188.0 and back.heading_unit[0] < -0.98  # looks back along -x


def test_a_walker_20_m_behind_pole_k_seen_by_its_backward_camera_lights_lamp_k_minus_1():
    night = build_night(load_scenario(TWO_WAY))
    controller = build_controller(night, ControllerSpec(name="detector_located"))
    for i in range(night.n_lamps):
        night.env.process(deliver_messages(night, controller, i))
    n, k = night.n_lamps, 5
    back_index = n + k
    cam = night.street.cameras[back_index].camera
    assert controller.detectors[back_index].camera == cam, "camera n+k's detector has the backward camera's pose"
    behind = cam.position_m[:2] + 20.0 * cam.heading_unit  # 20 m from the pole toward -x, on the ground
    zone = next(j for j, s in enumerate(night.street.lamps) if s.zone_start_m <= behind[0] < s.zone_end_m)
    assert zone == k - 1
    # placed with the forward camera's pose, the same pixels would stand ~20 m the other way, in zone k + 1
    wrong = night.street.cameras[k].camera.pixel_to_ground(np.array([[*walker_box_feet(cam, behind)]]))[0]
    assert wrong[0] > night.street.lamps[k + 1].zone_start_m
    detection = target_detection(walker_box(cam, behind))
    for frame in range(PAPER_N):  # confirmed: seen in 6 frames, a target in 2 of them
        controller.place(back_index, frame / 15, [detection])
    # pixel rounding: at 20 m one image row is ~0.25 m of ground (20^2 / (fy 324 px x 5.5 m)); the box's
    # feet are within a row of the projection, so 0.5 m
    track = controller.tracks[(back_index, 7)]
    assert abs(track.last[1] - behind[0]) < 0.5
    night.env.run(until=1.0)  # the radio's latency
    lamps = controller.ctx.lamps
    assert lamps[k - 1].target_level == 1.0, "the zone behind the pole is lit, over the radio from lamp k"
    assert controller.ctx.network.stats.delivered >= 1
    assert all(lamps[j].target_level < 1.0 for j in range(n) if j != k - 1)


def walker_box_feet(cam, ground_xy) -> tuple[float, float]:
    """The bottom-centre pixel of ``walker_box`` as ``place`` reads it."""
    x, y, w, h = walker_box(cam, ground_xy)
    return x + w / 2 - 0.5, y + h - 0.5


def test_the_backward_camera_is_busy_when_someone_walks_behind_its_pole():
    street = build_night(load_scenario(TWO_WAY)).street
    n, k = len(street.lamps), 4
    x_m = street.lamps[k].x_m - 15.0
    walker = AgentState(1, "pedestrian", x_m, 4.3, np.pi, 1.4, 0.5, 0.5, 1.7)
    busy = CameraSchedule(street, idle_stride=15).in_view([walker])
    # behind pole k: its backward camera and the forward camera of pole k - 1, nobody else
    assert set(np.flatnonzero(busy)) == {k - 1, n + k}


def test_the_fast_sensor_model_judges_both_cameras_of_every_pole():
    # tests/citysim/fast/test_two_cameras.py checks the figures; here the shipped scenario runs
    from tests.citysim.fast.synthetic import constant_model

    scenario = override(load_scenario(TWO_WAY), {"duration_s": 3})
    summary = run_controller(scenario, ControllerSpec(name="detector_located"), fidelity="fast",
                             sensor_model=constant_model(1.0))  # fmt: skip
    assert summary["controller"] == "detector_located"


def test_a_bad_back_heading_names_the_field():
    with pytest.raises((ScenarioError, FieldPathError), match="back_heading_deg"):
        override(load_scenario(TWO_WAY), {"lamps.camera.back_heading_deg": 400})


def test_with_a_backward_camera_on_the_first_pole_no_end_lamp_is_kept_lit():
    controller = build_controller(build_night(load_scenario(TWO_WAY)), ControllerSpec(name="detector_located"))
    assert controller.blind_end_lamps == []  # pole 0's backward camera watches the street's start
