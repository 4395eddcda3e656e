"""Light thrown on the road is no road user (``detector.tracks.plausibility``: 'too wide for its
heading'; ``detector.tracks.motion``: no vehicle by motion while coming toward the camera).

On the paper's scene C every noise track called a target was the light spot a lamp throws on the
road ahead of its road user: a cyclist's going away at 3.5-7 m/s, 3.5-4.6 m wide and 1.6-1.9 m
'tall'; a car's coming toward the camera at 8-12 m/s, 6-9 m wide. A cyclist or a car moving along
the line of sight shows its front or back, at most 1.8 m wide on 1.4 m high (Table 1), so a track
that fast, that way, that wide is light; a car crossing the view shows its side and may be as wide
as it is long."""

from __future__ import annotations

import pytest

from detector.classes import CLASSES
from detector.tracks.motion import MotionLimits, overriding_speed_mps, unsteady_because
from detector.tracks.plausibility import (
    FRONT_ASPECT,
    PlausibilityLimits,
    note_heading,
    reject_reason,
)
from detector.tracks.track import Track
from detector.tracks.tracker import TrackSet
from tests.detector.cameras import scene_b

FPS = 15.0
VEHICLE = [0.1, 0.0, 0.0, 0.1, 0.8]  # frames the classifier calls a vehicle (a car side on is as wide)
CYCLIST = [0.1, 0.0, 0.0, 0.8, 0.1]
NOISE = [1.0, 0.0, 0.0, 0.0, 0.0]


def _track(ground_at, size_m, probabilities, n_frames=15, judge_last=False) -> Track:
    """A track seen in ``n_frames`` frames at ground points ``ground_at(k)`` (forward, right, m) with
    estimated (width, height) ``size_m`` and class probabilities ``probabilities`` every frame, its
    heading noted each frame as the tracker does; with ``judge_last`` the last frame is judged by a
    ``TrackSet`` (which notes it)."""
    track = Track(1, 0, FPS, [100, 80, 120, 40], *ground_at(0))
    track.start([100, 80, 120, 40], ground_at(0), list(size_m), probabilities)
    for k in range(1, n_frames):
        track.observe(k, [100, 80 - k, 120, 40], ground_at(k), list(size_m), probabilities)
        if judge_last and k == n_frames - 1:
            TrackSet(scene_b(), CLASSES)._judge(track)
        else:
            note_heading(track, PlausibilityLimits())
    return track


def _going_away(speed_mps):
    return lambda k: (15.0 + speed_mps * k / FPS, 1.0)


def _coming(speed_mps):
    return lambda k: (40.0 - speed_mps * k / FPS, -1.5)


def _crossing(speed_mps):
    return lambda k: (12.0, -8.0 + speed_mps * k / FPS)


def test_the_front_aspect_is_a_vehicle_seen_from_behind():
    assert FRONT_ASPECT == pytest.approx(1.8 / 1.4)


def test_a_cyclist_lamps_spot_going_away_is_rejected_though_its_frames_say_vehicle():
    spot = _track(_going_away(5.5), (4.0, 1.7), VEHICLE)  # scene C's: 4 m wide at a cyclist's speed
    assert reject_reason(spot, PlausibilityLimits()) == "too wide for its heading"
    # steady and straight, but at a cyclist's speed its width is the lamp's light, not a car's body
    assert unsteady_because(spot, MotionLimits()) is None
    assert overriding_speed_mps(spot, "too wide for its heading", MotionLimits()) is None
    spot = _track(_going_away(5.5), (4.0, 1.7), VEHICLE, judge_last=True)
    assert not spot.target and spot.reason == "too wide for its heading"


def test_the_cyclist_behind_it_is_kept():
    cyclist = _track(_going_away(5.5), (0.8, 1.7), CYCLIST, judge_last=True)
    assert reject_reason(cyclist, PlausibilityLimits()) is None
    assert cyclist.target and cyclist.cls == "cyclist"


@pytest.mark.parametrize(
    ("ground_at", "size_m"),
    [
        (_crossing(10.0), (4.2, 1.6)),  # a car crossing the view shows its side: as wide as it is long
        (_coming(10.0), (2.2, 1.9)),  # a car coming head on, its lamps' glare widening it a little
        (_going_away(1.2), (2.8, 1.7)),  # a group walking away side by side (walkers: not judged so)
    ],
)
def test_road_users_as_wide_as_their_heading_allows_are_kept(ground_at, size_m):
    track = _track(ground_at, size_m, VEHICLE, judge_last=True)
    assert reject_reason(track, PlausibilityLimits()) is None
    assert track.target


def test_a_cars_spot_coming_toward_the_camera_is_no_vehicle_by_its_motion():
    # the spot a car's headlights throw ahead of it, 8 m wide, coming at 10 m/s: its frames noise
    spot = _track(_coming(10.0), (8.0, 3.0), NOISE, judge_last=True)
    assert unsteady_because(spot, MotionLimits()) == "coming toward the camera"
    assert not spot.target
    # the same spot going away is the car seen from behind (tests/detector/test_track_motion.py)
    away = _track(_going_away(10.0), (8.0, 3.0), NOISE, judge_last=True)
    assert unsteady_because(away, MotionLimits()) is None
    assert away.target and away.cls == "vehicle"


def test_a_wide_track_going_away_at_a_vehicles_speed_is_still_the_car_seen_from_behind():
    # a car's spot that fits Table 1's sizes (a car side on) but not a car's back: 'too wide for its
    # heading', which a vehicle's steady motion outweighs above walkers' and cyclists' speeds
    spot = _track(_going_away(11.0), (4.4, 1.8), NOISE)
    assert reject_reason(spot, PlausibilityLimits()) == "too wide for its heading"
    assert overriding_speed_mps(spot, "too wide for its heading", MotionLimits()) == pytest.approx(11.0, abs=0.1)
    spot = _track(_going_away(11.0), (4.4, 1.8), NOISE, judge_last=True)
    assert spot.target and spot.cls == "vehicle"


def test_a_spot_breathing_around_the_bound_stays_light_while_most_of_its_frames_were_too_wide():
    spot = _track(_going_away(5.5), (4.0, 1.7), VEHICLE, n_frames=20)
    assert spot.wide_frames == spot.head_on_frames > 10
    for k in range(20, 32):  # then twelve frames narrower: the light's outline, not a cyclist
        spot.observe(k, [100, 60, 120, 40], _going_away(5.5)(k), [0.9, 1.7], VEHICLE)
        note_heading(spot, PlausibilityLimits())
    wide_now = spot.wide_frames
    note_heading(spot, PlausibilityLimits())
    assert spot.wide_frames == wide_now  # its last frames alone are no longer too wide
    assert reject_reason(spot, PlausibilityLimits()) == "too wide for its heading"


def test_no_track_is_a_target_before_its_motion_is_known():
    young = _track(_going_away(5.5), (0.8, 1.7), CYCLIST, n_frames=5)  # 5 frames, 0.27 s
    assert young.velocity_mps is None
    assert reject_reason(young, PlausibilityLimits()) == "too few frames"


def test_limits_name_the_bad_field():
    with pytest.raises(ValueError, match="head_on_deg"):
        PlausibilityLimits(head_on_deg=90.0)
    with pytest.raises(ValueError, match="walk_max_mps"):
        PlausibilityLimits(walk_max_mps=0.0)
    with pytest.raises(ValueError, match="approach_deg"):
        MotionLimits(approach_deg=180.0)
