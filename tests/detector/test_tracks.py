"""Tracks: association on the ground, pooled classes, physical plausibility, fragments joined.

Synthetic clips (``tests.detector.clips``) through the real detector: its segmenter, features,
classifier and tracks.
"""

from __future__ import annotations

import math
from collections import Counter

import cv2
import numpy as np
import pytest

from detector.detector import Detector
from detector.general_model import default_model
from detector.tracks.plausibility import PlausibilityLimits, table1_misfit
from detector.tracks.track import pool_probabilities
from detector.train.shapes import pedestrian_shape, vehicle_shape
from detector.train.silhouette import silhouette_mask
from tests.detector.cameras import scene_b
from tests.detector.clips import Clip

FPS = 15.0


@pytest.fixture(scope="module")
def model():
    return default_model()


def test_mean_log_pooling_by_hand():
    frames = [[0.5, 0.5], [0.9, 0.1]]
    # geometric means sqrt(0.45) and sqrt(0.05), renormalised
    a, b = math.sqrt(0.45), math.sqrt(0.05)
    assert pool_probabilities(frames) == pytest.approx([a / (a + b), b / (a + b)])
    assert pool_probabilities(frames, "mean") == pytest.approx([0.7, 0.3])
    assert pool_probabilities(frames, "last") == [0.9, 0.1]
    with pytest.raises(ValueError, match="pooling: must be one of"):
        pool_probabilities(frames, "median")


def test_table1_misfit_is_zero_inside_a_class_and_grows_outside():
    assert table1_misfit(0.5, 1.75) == 0.0  # a pedestrian
    assert table1_misfit(4.2, 1.5) == 0.0  # a car side on
    assert table1_misfit(0.1, 0.2) > 0.5  # a speck
    assert table1_misfit(8.0, 1.5) > table1_misfit(5.0, 1.5) > 0.0


def test_limits_name_the_bad_field():
    with pytest.raises(ValueError, match="min_frames"):
        PlausibilityLimits(min_frames=0)
    with pytest.raises(ValueError, match="max_speed_mps"):
        PlausibilityLimits(max_speed_mps=-1.0)


def walker(forward_m, lateral_m, t_s):
    return pedestrian_shape(forward_m, lateral_m + 1.4 * t_s, math.pi / 2, 0.5, 1.75, 0.7, 2 * math.pi * 0.9 * t_s)


def test_walker_is_one_target_track_with_its_ground_position_and_speed(model):
    cam = scene_b(x_m=100.0, y_m=5.0, yaw_deg=90.0)  # looking along +y: forward is world y
    clip = Clip(cam, seed=1)
    det = Detector(cam, model=model)
    clip.warm_up(det)
    rows = []
    for k in range(45):
        t_s = k / FPS
        shape = pedestrian_shape(102.5 - 1.4 * t_s, 15.0, math.pi, 0.5, 1.75, 0.7, 5.65 * t_s)
        for d in det.process(clip.frame([shape])):
            rows.append((k, d))
    assert len({d.track_id for _, d in rows}) == 1
    late = [d for k, d in rows if k >= 10]
    assert all(d.track_target and d.track_cls == "pedestrian" for d in late)
    # walking to the camera's left (the world's -x here) 10 m ahead of it (world y = 15 m)
    assert np.median([d.speed_mps for d in late]) == pytest.approx(1.4, abs=0.2)
    assert np.median([d.velocity_x_mps for d in late]) == pytest.approx(-1.4, abs=0.2)
    assert np.median([d.ground_y_m for d in late]) == pytest.approx(15.0, abs=0.6)
    # the first frames are not a target yet: too few to judge
    assert rows[0][1].track_reason == "too few frames" and not rows[0][1].track_target


@pytest.mark.parametrize("seed", range(4))
def test_insect_near_the_lens_never_becomes_a_target_track(model, seed):
    # a bright moth fluttering close to the emitter: erratic, fast across the image, its size jumping
    cam = scene_b()
    clip = Clip(cam, seed=seed)
    det = Detector(cam, model=model)
    clip.warm_up(det)
    rng = np.random.default_rng(seed)
    pos, vel = np.array([160.0, 150.0]), np.zeros(2)
    per_frame_targets, reasons = 0, Counter()
    for _ in range(90):
        vel = 0.5 * vel + rng.normal(0, 14, 2)
        pos = np.clip(pos + vel, (40, 60), (280, 200))
        r = rng.uniform(4, 16)
        img = clip.frame()
        axes = (int(r), int(r * rng.uniform(1.5, 3.5)))
        cv2.ellipse(img, (int(pos[0]), int(pos[1])), axes, rng.uniform(0, 180), 0, 360, 200, -1)
        detections = det.process(img)
        per_frame_targets += any(d.p_target >= 0.5 for d in detections)
        assert not det.is_target(detections)
        assert not any(d.track_target for d in detections)
        reasons.update(d.track_reason for d in detections)
    # the frames alone would have lit the lamp: the tracks are what says no
    assert per_frame_targets >= 3, per_frame_targets
    physical = ("erratic", "jumping", "size outside Table 1", "size unsteady")
    assert sum(reasons[r] for r in physical) > 30, reasons


def test_walker_standing_still_for_5_s_keeps_its_track(model):
    cam = scene_b()
    clip = Clip(cam, seed=2)
    det = Detector(cam, model=model)
    clip.warm_up(det, 500)  # MOG2 past its start-up rate: it learns at its history's pace
    seen = []
    for k in range(int(8 * FPS)):
        t_s = k / FPS
        walked_s = min(t_s, 1.5) + max(0.0, t_s - 6.5)  # walks 1.5 s, stands 5 s, walks on
        shape = pedestrian_shape(12.0, -2.5 + 1.4 * walked_s, math.pi / 2, 0.5, 1.75, 0.7, 5.65 * walked_s)
        seen += [(k, d) for d in det.process(clip.frame([shape]))]
    ids = {d.track_id for _, d in seen}
    assert ids == {1}, ids
    standing = [d for k, d in seen if 1.5 * FPS + 10 <= k <= 6.5 * FPS]
    walking_on = [d for k, d in seen if k >= 7 * FPS]
    assert len(standing) >= 20 and len(walking_on) >= 10
    assert all(d.track_target for d in standing + walking_on)
    assert np.median([d.speed_mps for d in standing]) < 0.3


def split_car_frames(cam, clip, n_frames):
    """A car crossing side on at 4 m/s whose middle (dark windows, door line) matches the background."""
    for k in range(n_frames):
        car = vehicle_shape(14.0, -6.0 + 4.0 * k / FPS, math.pi / 2, 1.7, 1.5, 4.2)
        img = clip.frame([car])
        sil = silhouette_mask(cam, car)
        cx = sil.offset_px[0] + sil.mask.shape[1] // 2
        img[:, cx - 4 : cx + 4] = np.clip(clip.background[:, cx - 4 : cx + 4], 0, 255).astype(np.uint8)
        yield k, img


def test_two_fragments_of_one_car_moving_together_become_one_vehicle(model):
    cam = scene_b()
    per_frame, tracked = {}, {}
    for tracking, out in ((False, per_frame), (True, tracked)):
        clip = Clip(cam, seed=3)
        det = Detector(cam, model=model, tracking=tracking)
        clip.warm_up(det)
        for k, img in split_car_frames(cam, clip, 30):
            out[k] = det.process(img)
    # per frame, the car is two half-car regions from frame 8 on, neither called a vehicle
    assert all(len(per_frame[k]) == 2 for k in range(8, 30))
    assert not any(d.cls == "vehicle" for k in per_frame for d in per_frame[k])
    # with tracks the halves are one region again once both have moved together a few frames
    joined = range(15, 30)
    assert all(len(tracked[k]) == 1 for k in joined)
    assert all(tracked[k][0].cls == "vehicle" and tracked[k][0].box_px[2] > 100 for k in joined)
    assert all(tracked[k][0].track_cls == "vehicle" and tracked[k][0].track_target for k in range(22, 30))
    assert len({d.track_id for k in joined for d in tracked[k]}) == 1


def test_per_frame_path_has_no_tracks(model):
    cam = scene_b()
    clip = Clip(cam, seed=1)
    det = Detector(cam, model=model, tracking=False)
    assert det.tracks is None
    clip.warm_up(det)
    detections = []
    for k in range(20):
        detections += det.process(clip.frame([walker(10.0, -2.5, k / FPS)]))
    assert detections and all(d.track_p_target is None and d.ground_x_m is None for d in detections)
    assert det.is_target(detections)  # decided on each frame's own P(target)


def _track(track_id, box_px, image_velocity_px=(0.0, 0.0), sightings=5, ground=(10.0, 0.0)):
    from detector.tracks.track import Track

    track = Track(track_id, 0, FPS, list(box_px), *ground, sightings=sightings, last_frame=0)
    track.image_velocity_px = image_velocity_px
    return track


def test_a_piece_inside_a_continued_tracks_box_joins_it():
    from detector.tracks.reunite import ReuniteParams, fragment_groups

    body = _track(1, (100, 50, 40, 80), (2.0, 0.0))  # predicted at x = 102
    boxes = [(102, 50, 40, 60), (110, 112, 20, 18), (250, 60, 10, 30)]  # body, its legs, elsewhere
    rows = [[0.5, 1.7], [0.4, 0.4], [0.2, 0.5]]
    groups = fragment_groups([body], boxes, rows, [0, -1, -1], lambda idx: [0.5, 1.75], ReuniteParams())
    assert groups == [[0, 1]]  # the legs join the body's region; the far speck stays alone


def test_established_tracks_moving_together_join_only_if_the_union_fits_table1():
    from detector.tracks.reunite import ReuniteParams, fragment_groups

    front, back = _track(1, (100, 50, 50, 40), (-6.0, 0.0)), _track(2, (152, 50, 50, 40), (-6.2, 0.0))
    boxes = [(94, 50, 50, 40), (146, 50, 50, 40)]
    rows = [[2.0, 1.5], [2.0, 1.5]]
    params = ReuniteParams()
    # two halves of a car side on: the union (4.2 m x 1.5 m) is a vehicle
    assert fragment_groups([front, back], boxes, rows, [0, 1], lambda idx: [4.2, 1.5], params) == [[0, 1]]
    # a union no road user has the size of stays apart
    assert fragment_groups([front, back], boxes, rows, [0, 1], lambda idx: [9.0, 1.5], params) == []
    # moving apart: no join whatever the size
    back.image_velocity_px = (6.0, 0.0)
    assert fragment_groups([front, back], boxes, rows, [0, 1], lambda idx: [4.2, 1.5], params) == []
    # too young to say they move together
    back.image_velocity_px, back.sightings = (-6.2, 0.0), 2
    assert fragment_groups([front, back], boxes, rows, [0, 1], lambda idx: [4.2, 1.5], params) == []


def test_ground_gate_keeps_a_fast_car_whose_box_jumped():
    from detector.tracks.associate import Gates, associate

    car = _track(1, (100, 100, 30, 20), ground=(8.0, 0.0))
    car.velocity_mps = (0.0, 15.0)  # 1 m per frame across the view
    # next frame: the box moved 60 px (no overlap, two diagonals away) but the ground point is where predicted
    assert associate([car], [(160, 100, 30, 20)], [(8.0, 1.0)], 1, Gates()) == [0]
    # the same jump with the ground point 5 m off: no gate holds
    assert associate([car], [(160, 100, 30, 20)], [(8.0, 6.0)], 1, Gates()) == [-1]


def test_a_speck_beside_a_walker_does_not_continue_his_track():
    from detector.tracks.associate import Gates, associate

    walker_track = _track(1, (100, 40, 30, 70), ground=(9.0, 0.0))
    # this frame the body was not segmented; a 6 x 6 px speck lies by his feet (night_walk frame 218)
    assert associate([walker_track], [(118, 104, 6, 6)], [(9.2, 0.3)], 1, Gates()) == [-1]
    # his legs alone (a third of his box) still continue him
    assert associate([walker_track], [(102, 80, 28, 30)], [(9.0, 0.1)], 1, Gates()) == [0]
    with pytest.raises(ValueError, match="max_area_ratio"):
        Gates(max_area_ratio=0.5)


def test_after_a_legs_only_frame_the_prediction_keeps_the_whole_body():
    from detector.tracks.track import Track

    track = Track(1, 0, FPS, [100, 40, 30, 70], 9.0, 0.0)
    track.start([100, 40, 30, 70], (9.0, 0.0), [0.5, 1.75], [0.1, 0.9, 0.0, 0.0, 0.0])
    for k in range(1, 6):
        track.observe(k, [100 + 2 * k, 40, 30, 70], (9.0, 0.1 * k), [0.5, 1.75], [0.1, 0.9, 0.0, 0.0, 0.0])
    track.observe(6, [112, 80, 30, 30], (9.0, 0.6), [0.5, 0.7], [0.9, 0.1, 0.0, 0.0, 0.0])  # legs only
    x, y, w, h = track.predicted_box()
    assert (w, h) == (30, 70)  # the body's typical size, not the legs'
    assert y + h == pytest.approx(110, abs=1.0)  # standing on the bottom row the legs share with the body
    assert 112 < x + w / 2 - 15 < 118  # moving on to the right


def test_a_bottom_row_that_jumps_for_a_few_frames_is_no_burst_of_speed():
    from detector.tracks.track import Track

    fps = 30.0
    track = Track(1, 0, fps, [100, 40, 30, 70], 9.0, 0.0)
    track.start([100, 40, 30, 70], (9.0, 0.0), [0.5, 1.75], [0.1, 0.9, 0.0, 0.0, 0.0])
    speeds = []
    for k in range(1, 60):
        lateral_m = 1.4 * k / fps  # a walker at 1.4 m/s
        # frames 30-32: the box swallows a reflection below his feet, the ground point 3 m nearer
        forward_m = 6.0 if 30 <= k <= 32 else 9.0
        track.observe(k, [100 + k, 40, 30, 70], (forward_m, lateral_m), [0.5, 1.75], [0.1, 0.9, 0.0, 0.0, 0.0])
        if track.speed_mps is not None:
            speeds.append(track.speed_mps)
    assert max(speeds) < 2.0, max(speeds)  # through the end points: 3 m in half a second, 6 m/s
    assert np.median(speeds) == pytest.approx(1.4, abs=0.05)
