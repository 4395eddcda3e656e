"""The world on a curved street (scenarios/curved_bend.yaml), against hand-computed values.

The bend: centreline (0, 0) -> (180, 0) -> (180, 180), a left turn at s = 180 m, cross-sections
blended over 30 m either side (``world.centreline``). Lamp 4 stands at s = 165 m, d = 6.2 m: in the
blend half-way, its cross-section is (0, 1) / 2 + (-1, 1) / 2 = (-0.5, 1), so the pole is at
(165 - 3.1, 6.2) = (161.9, 6.2), its camera looking along the street (east) turned -8 deg.
"""

import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from citysim.config.scenario import ControllerSpec, load_scenario
from citysim.render.camera import CameraRenderer
from citysim.sim.loop import build_controller
from citysim.sim.night import build_night
from citysim.world.agents import AgentState
from citysim.world.street import build_street

SCENARIO = load_scenario(Path(__file__).resolve().parents[3] / "scenarios" / "curved_bend.yaml")
STREET = build_street(SCENARIO)
WALK_D_M = 4.3  # the inner (left) sidewalk's centre line


def test_poles_and_cameras_stand_where_the_centreline_puts_them():
    lamp = STREET.lamps[4]
    assert (lamp.along_m, lamp.offset_m) == (165.0, 6.2)
    assert (lamp.x_m, lamp.y_m) == pytest.approx((161.9, 6.2), abs=1e-12)
    assert lamp.camera.yaw_deg == pytest.approx(-8.0)
    # lamp 5 at s = 195 m on the right (d = -6.2 m), past the bend: its cross-section is
    # (2/3)(-1, 1) + (1/3)(-1, 0) = (-1, 2/3) at t = 1/2 of the blend; heading north turned +8 deg
    lamp = STREET.lamps[5]
    assert (lamp.x_m, lamp.y_m) == pytest.approx((180.0 + 6.2, 15.0 - 6.2 * 0.5), abs=1e-12)
    assert lamp.camera.yaw_deg == pytest.approx(98.0)
    # surveyed per-pole fields
    assert STREET.lamps[3].rated_power_w == 40.0 and STREET.lamps[6].pole_height_m == 6.0
    assert STREET.lamps[6].camera.height_m == 6.0


@pytest.mark.parametrize(
    ("s_m", "world_xy_m"),
    [
        (175.0, (175.0 - WALK_D_M * 5 / 6, WALK_D_M)),  # blend t = 5/6: cross-section (-5/6, 1)
        (180.0, (180.0 - WALK_D_M, WALK_D_M)),  # on the bisector
        (190.0, (180.0 - WALK_D_M, 10.0 + WALK_D_M * 2 / 3)),  # after it: (-1, 2/3) at t = 1/3
    ],
)
def test_a_walker_following_the_bend_is_seen_by_the_camera_whose_view_the_bend_lies_in(s_m, world_xy_m):
    walker = AgentState(1, "pedestrian", s_m, WALK_D_M, 0.0, 1.4, 0.3, 0.5, 1.75)  # street coordinates
    (placed,) = STREET.in_world([walker])
    assert (placed.x_m, placed.y_m) == pytest.approx(world_xy_m, abs=1e-9)
    levels = [1.0] * len(STREET.lamps)
    seen_by = {}
    for lamp in (2, 4, 5):
        renderer = CameraRenderer(STREET.lamps[lamp].camera, STREET, SCENARIO.environment, np.random.default_rng(0))
        # seen: in the frame within the detector's 25 m range (the truth lists farther ones too)
        truth = renderer.render(0.0, [placed], levels).truth
        seen_by[lamp] = [t for t in truth if t.object_id == 1 and t.distance_m <= 25.0]
    assert seen_by[2] == [] and seen_by[5] == []  # 60 m back; looking away (north from s = 195 m)
    (truth,) = seen_by[4]
    # the forward ground distance from the pole (161.9, 6.2) along the heading -8 deg, by hand
    yaw = math.radians(-8.0)
    forward_m = (world_xy_m[0] - 161.9) * math.cos(yaw) + (world_xy_m[1] - 6.2) * math.sin(yaw)
    assert truth.distance_m == pytest.approx(forward_m, abs=1e-9)
    assert 5.0 < forward_m < 25.0 and truth.fully_visible


def test_zone_boundaries_on_the_bend_follow_the_bisector():
    assert (STREET.lamps[4].zone_start_m, STREET.lamps[4].zone_end_m) == (150.0, 180.0)
    assert (STREET.lamps[5].zone_start_m, STREET.lamps[5].zone_end_m) == (180.0, 210.0)
    line = STREET.centreline
    # the boundary s = 180 m is the bisector x = 180 - y inside the bend (and x = 180 + |y| outside)
    s_before, d_before = line.to_sd(176.9, 3.0)  # 0.1 m before it: in the blend, t = 26.9 / 27
    assert (s_before, d_before) == pytest.approx((150.0 + 30.0 * 26.9 / 27.0, 3.0), abs=1e-9)
    s_after, d_after = line.to_sd(177.0, 3.1)  # 0.1 m after it, on the second segment: t = 0.1 / 27
    assert (s_after, d_after) == pytest.approx((180.0 + 30.0 * 0.1 / 27.0, 3.0), abs=1e-9)
    s_out, _ = line.to_sd(182.8, -2.9)  # outside the bend, 0.1 m before the bisector x = 180 + |y|
    assert s_out < 180.0
    zone = [next(i for i, lamp in enumerate(STREET.lamps) if lamp.zone_start_m <= s < lamp.zone_end_m)
            for s in (s_before, s_after, s_out)]  # fmt: skip
    assert zone == [4, 5, 4]


def test_the_oracles_lead_is_measured_along_the_curve():
    oracle = build_controller(build_night(SCENARIO), ControllerSpec(name="oracle"))
    lum = SCENARIO.lamps.luminaire
    lead_s = (1.0 - lum.dim_level) * lum.ramp_up_s + 2.0 / SCENARIO.physics_hz
    assert oracle.lead_s == pytest.approx(lead_s)
    # a car at 10 m/s along +s, accelerating at most 1.5 m/s^2: it reaches 10 lead + 0.75 lead^2 ahead
    reach_m = 10.0 * lead_s + 0.5 * 1.5 * lead_s**2
    assert reach_m == pytest.approx(3.1372, abs=1e-4)

    def needed(s_m: float) -> list[int]:
        car = AgentState(7, "vehicle", s_m, -1.6, 0.0, 10.0, 4.5, 1.8, 1.5)  # street coordinates
        return oracle.zones_needed([car]).tolist()

    # the bend's zone boundary (s = 180 m) is 3.14 m of curve ahead, wherever that is in the world
    assert needed(180.0 - reach_m + 0.05) == [4, 5]
    assert needed(180.0 - reach_m - 0.05) == [4]


def test_a_camera_on_the_curve_projects_as_opencv_does_and_round_trips_to_the_millimetre():
    cam = STREET.lamps[5].camera  # heading 98 deg: looking north, turned toward the road
    s_m = np.linspace(200.0, 225.0, 6)
    d_m = np.array([-4.3, -1.6, 0.0, 1.6, 4.3, -3.0])
    x_m, y_m = STREET.centreline.to_xy(s_m, d_m)
    ground = np.column_stack([x_m, y_m, np.zeros_like(x_m)])
    px = cam.project(ground)
    px_cv, _ = cv2.projectPoints(ground, cam.rvec, cam.tvec, cam.intrinsic_matrix, cam.distortion)
    assert np.abs(px - px_cv.reshape(-1, 2)).max() < 1e-6
    inside = (px[:, 0] >= 0) & (px[:, 0] < cam.width_px) & (px[:, 1] >= 0) & (px[:, 1] < cam.height_px)
    assert inside.all()
    back = cam.pixel_to_ground(px)
    assert np.abs(back[:, :2] - ground[:, :2]).max() < 1e-3
    s_back, d_back = STREET.centreline.to_sd(back[:, 0], back[:, 1])
    assert np.abs(s_back - s_m).max() < 1e-3 and np.abs(d_back - d_m).max() < 1e-3
