"""A track that moves like a road vehicle is a target (``detector.tracks.motion``): a car's
headlight spot going away from the camera, whose frames are all 'noise' of no Table 1 size, is
confirmed as a vehicle; a walker-slow or insect-jumpy track is not."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from detector.classes import CLASSES
from detector.detector import Detector
from detector.general_model import default_model
from detector.tracks.motion import (
    MotionLimits,
    line_fit,
    motion_class,
    steady_speed_mps,
    unsteady_because,
)
from detector.tracks.plausibility import PlausibilityLimits, reject_reason
from detector.tracks.track import Track
from detector.tracks.tracker import TrackSet
from tests.detector.cameras import scene_b
from tests.detector.clips import Clip

FPS = 15.0
NOISE = [1.0, 0.0, 0.0, 0.0, 0.0]  # every frame classified noise


def _track(ground_at, size_m=(8.0, 3.0), n_frames=15, fps=FPS) -> Track:
    """A track seen in ``n_frames`` frames at ground points ``ground_at(k)`` (forward, right, m), every
    frame of size ``size_m`` (width, height, m) and classified noise."""
    track = Track(1, 0, fps, [100, 80, 120, 40], *ground_at(0))
    track.start([100, 80, 120, 40], ground_at(0), list(size_m), NOISE)
    for k in range(1, n_frames):
        track.observe(k, [100, 80 - k, 120, 40], ground_at(k), list(size_m), NOISE)
    return track


def _spot_going_away(k, fps=FPS):
    # the near edge of a car's headlight spot, 10 m/s away from the camera; its fuzzy edge stalls and
    # jumps a pixel row or two (+-0.4 m at 15 m), as on suburban_night's renders
    jitter_m = (0.0, 0.4, -0.3, 0.2, -0.4, 0.3)[k % 6]
    return 10.0 + 10.0 * k / fps + jitter_m, 1.5


def test_a_car_spot_moving_steadily_away_is_a_vehicle_though_its_frames_look_like_noise():
    track = _track(_spot_going_away)
    # the frame rules alone reject it: 8 m wide, 3 m 'tall' fits no Table 1 class
    assert reject_reason(track, PlausibilityLimits()) == "size outside Table 1"
    assert steady_speed_mps(track, MotionLimits()) is not None
    tracks = TrackSet(scene_b(), CLASSES)
    tracks._judge(track)
    assert track.target and track.reason is None
    assert track.cls == "vehicle"  # 10 m/s: faster than walkers and cyclists go


def test_with_the_motion_rule_off_the_spot_stays_rejected_by_its_size():
    track = _track(_spot_going_away)
    TrackSet(scene_b(), CLASSES, motion=MotionLimits(enabled=False))._judge(track)
    assert not track.target and track.reason == "size outside Table 1"


def test_the_straight_line_fit_recovers_the_speed_through_the_jitter():
    vf, vr, residual_m, forward_m = line_fit([(k / FPS, *_spot_going_away(k)) for k in range(15)])
    assert vf == pytest.approx(10.0, abs=0.5) and abs(vr) < 0.1
    assert 0.2 < residual_m < 0.4 and forward_m == pytest.approx(14.7, abs=0.2)


def test_a_young_track_is_not_judged_by_its_motion():
    track = _track(_spot_going_away, n_frames=6)  # 0.33 s
    assert unsteady_because(track, MotionLimits()) == "too young"


@pytest.mark.parametrize(
    ("ground_at", "why"),
    [
        (lambda k: (10.0 + 1.0 * k / FPS, 1.5), "speed out of range"),  # a walker's pace: no vehicle
        (lambda k: (10.0 + 3.5 * k / FPS, 1.5), "speed out of range"),  # a jogger's flashlight spot
        (lambda k: (10.0 + 30.0 * k / FPS, 1.5), "speed out of range"),  # 108 km/h: nothing on a town street
        # an insect near the lens: its ground point jumps metres between frames
        (lambda k: (10.0 + 10.0 * k / FPS + (4.0 if k % 2 else -4.0), 1.5 + 3.0 * math.sin(k)), "not a straight steady path"),
    ],
)
def test_slow_fast_or_jumpy_tracks_are_not_taken_for_vehicles(ground_at, why):
    track = _track(ground_at)
    assert unsteady_because(track, MotionLimits()) == why
    tracks = TrackSet(scene_b(), CLASSES)
    tracks._judge(track)
    assert not track.target


def test_size_jumps_or_a_whole_view_region_are_no_vehicle():
    track = _track(_spot_going_away)
    for k, w in zip(range(15, 21), (8.0, 2.0, 9.0, 1.5, 8.0, 2.5), strict=True):  # an insect's flutter
        track.observe(k, [100, 60, 120, 40], _spot_going_away(k), [w, 3.0], NOISE)
    assert unsteady_because(track, MotionLimits()) == "size unsteady"
    assert unsteady_because(_track(_spot_going_away, size_m=(20.0, 3.0)), MotionLimits()) == "too big"
    # a piece of a cyclist or a car, or a low speck, moving at a vehicle's speed: no vehicle by motion
    assert unsteady_because(_track(_spot_going_away, size_m=(0.5, 0.7)), MotionLimits()) == "too small"
    assert unsteady_because(_track(_spot_going_away, size_m=(3.0, 0.7)), MotionLimits()) == "too small"


def test_motion_class_is_the_classifiers_below_vehicle_speed():
    limits = MotionLimits()
    assert motion_class(steady_speed_mps(_track(_spot_going_away), limits), "cyclist", limits) == "vehicle"
    slow = _track(lambda k: (10.0 + 6.0 * k / FPS, 1.5))  # an e-scooter's 22 km/h
    assert motion_class(steady_speed_mps(slow, limits), "cyclist", limits) == "cyclist"


def test_motion_limits_name_the_bad_field():
    with pytest.raises(ValueError, match="min_points"):
        MotionLimits(min_points=2)
    with pytest.raises(ValueError, match="min_height_m"):
        MotionLimits(min_height_m=0.0)
    with pytest.raises(ValueError, match="max_residual_share"):
        MotionLimits(max_residual_share=0.0)
    with pytest.raises(ValueError, match="min_speed_mps < max_speed_mps"):
        MotionLimits(min_speed_mps=25.0)


def _spot_polygon(cam, near_m, lateral_m, length_m=9.0, half_width_m=2.5):
    """The outline, in pixels, of a flat headlight spot on the road from ``near_m`` to ``near_m + length_m``."""
    t = np.linspace(0.0, 2.0 * math.pi, 40)
    ground = np.stack([near_m + length_m / 2 * (1 + np.cos(t)), lateral_m + half_width_m * np.sin(t), np.zeros_like(t)], 1)
    return cam.project(ground).round().astype(np.int32)


def test_detector_confirms_a_headlight_spot_going_away_within_a_second():
    # a car going away shows mostly the spot its headlights throw ahead of it: flat, wide, bright;
    # its frames are classified noise once the first few have passed
    cam = scene_b()
    clip = Clip(cam, seed=3)
    det = Detector(cam, model=default_model())
    clip.warm_up(det)
    frames = []
    for k in range(int(1.5 * FPS)):
        img = clip.frame()
        cv2.fillPoly(img, [_spot_polygon(cam, 7.0 + 10.0 * k / FPS, 0.0)], 110)
        frames.append(det.process(img))
    after_a_second = frames[int(FPS) - 5:]
    assert all(len(ds) == 1 for ds in after_a_second)
    assert sum(ds[0].p_target < 0.5 for ds in after_a_second) >= 8  # the frames alone say noise
    assert all(ds[0].track_target and ds[0].track_cls == "vehicle" for ds in after_a_second)
    assert np.median([ds[0].velocity_x_mps for ds in after_a_second]) == pytest.approx(10.0, abs=1.5)
