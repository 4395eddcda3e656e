"""Street coordinates on a polyline with a 90-degree bend, and the picture's zones and camera views,
against hand computations."""

from __future__ import annotations

import math

import pytest

from citysim.gis.geometry import offset_point, project, self_intersection, sharpest_turn_deg
from citysim.gis.picture import blind_stretches_m, footprint_m, zone_bounds_m

BEND = [(0.0, 0.0), (100.0, 0.0), (100.0, 80.0)]  # east 100 m, then north 80 m


@pytest.mark.parametrize(("point", "s_d"), [
    ((30.0, 7.0), (30.0, 7.0)),      # left of the eastward leg
    ((70.0, -6.5), (70.0, -6.5)),    # right of it
    ((107.0, 40.0), (140.0, -7.0)),  # east of the northward leg: its right
    ((93.0, 50.0), (150.0, 7.0)),    # west of it: its left
])
def test_projection_gives_s_along_and_d_to_the_left(point, s_d):
    s, d, beyond = project(BEND, point)
    assert (s, d) == pytest.approx(s_d, abs=1e-9) and beyond == 0.0


def test_a_point_beyond_the_end_says_how_far_beyond():
    s, d, beyond = project(BEND, (100.0, 90.0))
    assert s == pytest.approx(180.0) and beyond == pytest.approx(10.0)


def test_offset_point_inverts_the_projection():
    x, y = offset_point(BEND, 140.0, -7.0)
    assert (x, y) == pytest.approx((107.0, 40.0))


def test_turns_and_crossings():
    assert sharpest_turn_deg(BEND) == (pytest.approx(90.0), 1)
    assert self_intersection(BEND) is None
    assert self_intersection([(0, 0), (10, 0), (10, -10), (5, 5)]) is not None


def test_zones_cut_half_way_between_lamps():
    assert zone_bounds_m([30.0, 70.0, 140.0], 180.0) == [(10.0, 50.0), (50.0, 105.0), (105.0, 175.0)]


def test_a_camera_footprint_starts_where_the_bottom_row_meets_the_ground():
    camera = {"tilt_deg": 15.0, "focal_mm": 3.67, "sensor_w_mm": 4.8, "sensor_h_mm": 3.6}
    poly = footprint_m(0.0, 0.0, 5.0, 0.0, camera)
    # bottom row's depression: tilt + atan(1.8 / 3.67) = 15 + 26.12 deg; on the optical axis's column
    near_m = 5.0 / math.tan(math.radians(15.0 + math.degrees(math.atan(1.8 / 3.67))))
    assert poly[:, 0].min() == pytest.approx(near_m, abs=0.05)
    assert poly[:, 0].max() == pytest.approx(25.0, abs=1e-6)  # the top row is above the horizon: cut at 25 m
    assert abs(poly[:, 1]).max() <= 25.0


def test_blind_stretches_are_where_no_camera_looks():
    camera = {"tilt_deg": 15.0, "focal_mm": 3.67, "sensor_w_mm": 4.8, "sensor_h_mm": 3.6}
    data = {"street": {"centreline_m": [[0, 0], [100, 0]]},
            "lamps": {"poles": [{"s_m": 10.0, "d_m": 0.0}], "pole_height_m": 5.0, "camera": camera}}
    blind, covered = blind_stretches_m(data)
    near_m = 5.0 / math.tan(math.radians(15.0 + math.degrees(math.atan(1.8 / 3.67))))
    assert blind[0][0] == 0.0 and blind[0][1] == pytest.approx(10.0 + near_m, abs=0.5)
    assert blind[1] == (pytest.approx(35.0, abs=0.5), pytest.approx(100.0))
    assert covered == pytest.approx((25.0 - near_m) / 100.0, abs=0.01)
