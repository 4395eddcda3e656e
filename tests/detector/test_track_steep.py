"""Steep cameras: a track's size, class and target decision by its footprint on the ground
(``detector.tracks.steep``).

Synthetic input: boxes made by projecting bodies through the car-park clip's camera (10 m up, 50
degrees down) and tracks fed by hand with chosen classifier probabilities, so each rule is seen
alone, and beside it the paper's upright-body rules on the same input.
"""

from __future__ import annotations

import math

import pytest

from detector.features import RegionGeometry
from detector.tracks.footprint import FootprintGeometry, FootprintParams
from detector.tracks.steep import (
    FOOTPRINT_MAX_M,
    footprint_class,
    least_sides_m,
    piece_shift_share,
    size_reason,
    vehicle_min_m,
)
from detector.tracks.track import Track
from detector.tracks.tracker import TrackSet
from tests.detector.test_track_footprint import CLASSES, car_box_px, steep_camera

#: what the classifier says of a car seen from above: a group (its upright-body size), sure of it
LOOKS_LIKE_A_GROUP = [0.01, 0.02, 0.9, 0.02, 0.05]
#: a walker's frame where his whole body was segmented, and one where only his legs were
WHOLE_WALKER = [0.2, 0.7, 0.05, 0.04, 0.01]
LEGS_ONLY = [0.999, 0.0005, 0.0002, 0.0002, 0.0001]
TOLERANCE = 0.35  # PlausibilityLimits.size_tolerance


def walker_box_px(camera, forward_m, right_m):
    """An upright walker 0.5 m wide, 0.4 m deep, 1.7 m tall."""
    return car_box_px(camera, forward_m, right_m, heading_deg=0.0, length_m=0.4, width_m=0.5, height_m=1.7)


def run(tracks, boxes_and_probabilities):
    """Feed one region a frame; the views of the last frame."""
    views = []
    for box, probabilities in boxes_and_probabilities:
        rows = tracks.geometry.rows([box], [0.7 * box[2] * box[3]])
        prepared = tracks.prepare([list(box)], [0.7 * box[2] * box[3]], rows)
        views = tracks.update(prepared, [probabilities] * len(prepared.rows))
    return views


def test_largest_footprints_come_from_table1():
    assert FOOTPRINT_MAX_M["vehicle"] == pytest.approx((math.hypot(1.8, 4.6), (1.8 + 4.6) / math.sqrt(2)))
    assert FOOTPRINT_MAX_M["pedestrian"] == pytest.approx((math.hypot(0.64, 0.79), (0.64 + 0.79) / math.sqrt(2)))
    assert vehicle_min_m(TOLERANCE) == pytest.approx((3.7 * 0.65, 1.4 * 0.65))


def test_least_footprint_is_a_cars_size_and_a_walkers_without_the_roof_parallax():
    camera = steep_camera()
    footprints = FootprintGeometry(camera, RegionGeometry(camera), FootprintParams())
    for heading_deg, (depth_lo, depth_hi, width_lo, width_hi) in ((90.0, (3.4, 4.4, 1.6, 2.2)),
                                                                  (0.0, (1.2, 1.8, 3.4, 4.8))):  # fmt: skip
        (depth_m, width_m), = least_sides_m(footprints, [car_box_px(camera, 8.0, 0.0, heading_deg)])
        assert depth_lo <= depth_m <= depth_hi and width_lo <= width_m <= width_hi, heading_deg
    # a walker far up the view, off the centre: the hull of the box's corners on the ground and the
    # roof plane spans metres, his least footprint is his size
    box = walker_box_px(camera, 13.0, -5.0)
    (depth_m, width_m), = least_sides_m(footprints, [box])
    near, far, left, right = footprints.extents_m([box])[0]
    assert depth_m < 0.4 and width_m < 1.0
    assert max(far - near, right - left) > 1.5 * max(depth_m, width_m)


def _track_with(footprints_m, log_probabilities):
    track = Track(1, 0, 12.0, [0, 0, 10, 10], 8.0, 0.0)
    track.footprints_m.extend(footprints_m)
    track.log_sums = list(log_probabilities)
    return track


def test_size_and_class_by_footprint():
    likes_group = [math.log(p) for p in LOOKS_LIKE_A_GROUP]
    car = _track_with([(3.0, 2.3)] * 10, likes_group)  # the car-park clip's cars measure so
    assert size_reason(car, TOLERANCE) is None and footprint_class(car, CLASSES, TOLERANCE) == "vehicle"
    # pieces in most frames: the upper quartile, not the median, reaches a vehicle
    pieces = _track_with([(2.6, 0.4)] * 9 + [(3.0, 2.3)] * 6, likes_group)
    assert footprint_class(pieces, CLASSES, TOLERANCE) == "vehicle"
    once = _track_with([(2.6, 0.4)] * 14 + [(3.0, 2.3)], likes_group)  # one wrongly joined frame
    assert footprint_class(once, CLASSES, TOLERANCE) != "vehicle"
    walker = _track_with([(0.8, 0.05)] * 10, [math.log(p) for p in WHOLE_WALKER])
    assert size_reason(walker, TOLERANCE) is None and footprint_class(walker, CLASSES, TOLERANCE) == "pedestrian"
    # a walker's footprint fits no vehicle: the classifier's likeliest among the classes it fits
    assert footprint_class(_track_with([(0.8, 0.05)] * 10, likes_group), CLASSES, TOLERANCE) == "group"
    huge = _track_with([(9.0, 7.0)] * 10, likes_group)
    assert size_reason(huge, TOLERANCE) == "footprint outside Table 1"
    assert size_reason(_track_with([], likes_group), TOLERANCE) == "footprint outside Table 1"


def test_a_piece_inside_its_bodys_outline_is_no_jump():
    track = Track(1, 0, 12.0, [100, 50, 30, 32], 8.0, 0.0)
    track.start([100, 50, 30, 32], (8.0, 0.0), [0.6, 1.7, 0.3, 8.0], WHOLE_WALKER)
    # then his legs alone, two frames, a step on: the piece moves 6 px, three quarters of its size
    track.observe(1, [104, 74, 8, 8], (8.0, 0.1), [0.2, 0.3, 0.1, 8.0], LEGS_ONLY)
    track.observe(2, [110, 74, 8, 8], (8.0, 0.2), [0.2, 0.3, 0.1, 8.0], LEGS_ONLY)
    assert track.shift_share == pytest.approx(0.75)  # the paper's measure: a jump
    assert piece_shift_share(track) == pytest.approx(6 / 30)  # within the body's 30 px outline


def test_a_car_seen_from_above_is_one_vehicle_target_where_the_upright_rules_reject_it():
    camera = steep_camera()
    frames = [(car_box_px(camera, 6.0 + 0.2 * k, -0.5), LOOKS_LIKE_A_GROUP) for k in range(30)]
    (view,) = run(TrackSet(camera, CLASSES), frames)
    assert view.target and view.cls == "vehicle"
    # without the footprint (the paper's upright-body rules): not a target
    (view,) = run(TrackSet(camera, CLASSES, footprint=None), frames)
    assert not view.target and view.reason == "size outside Table 1"


def test_a_walker_in_pieces_is_a_target_by_his_whole_frames_and_noise_is_not():
    camera = steep_camera()
    frames = []
    for k in range(30):  # 1.5 m/s across the view, only his legs segmented in two frames of three
        x, y, w, h = walker_box_px(camera, 10.0, -3.0 + 0.125 * k)
        whole = k % 3 == 0
        frames.append(([x, y, w, h] if whole else [x, y + 2 * h // 3, w, h - 2 * h // 3],
                       WHOLE_WALKER if whole else LEGS_ONLY))  # fmt: skip
    tracks = TrackSet(camera, CLASSES)
    (view,) = run(tracks, frames)
    assert view.target and view.cls == "pedestrian"
    assert view.p_target < tracks.target_threshold  # the pooled P(target) alone would not do
    (view,) = run(TrackSet(camera, CLASSES), [(box, LEGS_ONLY) for box, _ in frames])
    assert not view.target and view.reason == "classified noise"
