"""detector_confirmed per track: k of n frames of one plausible track, its window full first.

The unit tests drive ``TrackWindows`` and ``plausible_marks`` by hand; the last ones run the real
detector on the moths of ``tests/detector/test_track_insects.py`` (recorded on suburban_night at
02:00) and on a walker, and ask what detector_confirmed's windows make of them.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from citysim.control.track_windows import (
    FRAGMENT_M,
    PAPER_K,
    PAPER_N,
    TrackWindows,
    fragment_keys,
    frame_hit,
    plausible_marks,
)
from detector.detector import Detector
from detector.general_model import default_model
from detector.train.shapes import pedestrian_shape
from tests.detector.test_track_insects import (
    CROSSING_MOTH,
    LOOPING_MOTH,
    moth_sequence,
    warmed_up,
)


def det(track_id, p_target=0.9, reason="too few frames", target=False, x_m=10.0, y_m=0.0):
    """A detection as the controllers read it (only the fields they use)."""
    return SimpleNamespace(track_id=track_id, p_target=p_target, track_reason=reason, track_target=target,
                           ground_x_m=x_m, ground_y_m=y_m)  # fmt: skip


def test_a_young_track_confirms_only_once_seen_in_n_frames():
    windows = TrackWindows(PAPER_K, PAPER_N, full_window=True)
    # target in its first two frames: two hits, but seen in 2 frames of the 6 it must be seen in
    assert windows.update({1: True}) == set()
    assert windows.update({1: True}) == set()
    for _ in range(3):
        assert windows.update({1: False}) == set()
    assert windows.update({1: False}) == {1}  # sixth sighting: both hits still in the window
    assert windows.update({1: False}) == set()  # the first hit left the window


def test_a_track_a_physics_rule_rules_out_loses_its_hits():
    windows = TrackWindows(PAPER_K, PAPER_N, full_window=True)
    for _ in range(5):
        windows.update({1: True})
    assert windows.update({1: None}) == set()  # 'jumping' at its sixth sighting: no confirmation
    assert windows.update({1: True}) == set()  # one hit since
    assert windows.update({1: True}) == {1}  # the rule no longer holds (its jumps left the last second)


def test_frame_hits_count_the_frames_class_unless_the_track_is_ruled_out():
    assert frame_hit(det(1, 0.9, "too few frames"), 0.5) is True  # velocity not known yet: the frame decides
    assert frame_hit(det(1, 0.9, "size outside Table 1"), 0.5) is True
    assert frame_hit(det(1, 0.2, None, target=True), 0.5) is True  # its track is a target
    assert frame_hit(det(1, 0.2, "classified noise"), 0.5) is False
    for reason in ("jumping", "too fast", "erratic", "size unsteady", "oscillating in place"):
        assert frame_hit(det(1, 0.99, reason), 0.5) is None
    # one ruled-out detection rules its track out for the frame
    assert plausible_marks([det(1, 0.9), det(1, 0.9, "jumping"), det(2, 0.1)], 0.5) == {1: None, 2: False}


def test_a_young_fragment_on_an_established_track_counts_for_it():
    windows = TrackWindows(PAPER_K, PAPER_N, full_window=True)
    for _ in range(PAPER_N):
        windows.update({7: False})  # a car's track, seen in 6 frames, no target frame yet
    car = det(7, 0.3, "size outside Table 1", x_m=40.0, y_m=-1.6)
    piece = det(9, 0.8, "too few frames", x_m=40.0 + FRAGMENT_M - 0.5, y_m=-1.6)
    far = det(11, 0.8, "too few frames", x_m=40.0 + FRAGMENT_M + 0.5, y_m=-1.6)
    assert fragment_keys([car, piece, far], windows) == [7, 7, 11]
    marks = plausible_marks([car, piece, far], 0.5, fragment_keys([car, piece, far], windows))
    assert marks == {7: True, 11: True}
    windows.update(marks)
    assert windows.update(marks) == {7}  # the car, by its pieces; the far one is not seen enough


@pytest.fixture(scope="module")
def model():
    return default_model()


def confirmations(detector: Detector, frames) -> tuple[int, int]:
    """(frames confirmed per track, frames confirmed per frame) of detector_confirmed's 2 of 6."""
    per_track = TrackWindows(PAPER_K, PAPER_N, full_window=True)
    per_frame = TrackWindows(PAPER_K, PAPER_N)
    n_track = n_frame = 0
    for image in frames:
        detections = detector.process(image)
        keys = fragment_keys(detections, per_track)
        n_track += bool(per_track.update(plausible_marks(detections, 0.5, keys)))
        n_frame += bool(per_frame.update({None: any(d.p_target >= 0.5 for d in detections)}))
    return n_track, n_frame


@pytest.mark.slow
@pytest.mark.parametrize("moth", [LOOPING_MOTH, CROSSING_MOTH], ids=["looping", "crossing"])
@pytest.mark.parametrize("seed", range(3))
def test_a_moth_at_the_emitter_never_confirms_a_track(model, moth, seed):
    clip, detector = warmed_up(model, seed)
    n_track, n_frame = confirmations(detector, moth_sequence(clip, moth, np.random.default_rng(seed)))
    assert n_track == 0
    assert n_frame >= 1, "the frame-by-frame window is fooled: the moth looks like a road user"


@pytest.mark.slow
def test_a_walker_is_confirmed_by_the_seventh_frame(model):
    clip, detector = warmed_up(model, 5)
    frames = []
    for k in range(30):
        t_s = k / 15.0
        frames.append(clip.frame([pedestrian_shape(14.0 - 1.4 * t_s, -0.5, math.pi, 0.5, 1.75, 0.7, 5.65 * t_s)]))
    per_track = TrackWindows(PAPER_K, PAPER_N, full_window=True)
    confirmed_at = None
    for k, image in enumerate(frames):
        detections = detector.process(image)
        if per_track.update(plausible_marks(detections, 0.5, fragment_keys(detections, per_track))):
            confirmed_at = k if confirmed_at is None else confirmed_at
    # seen in 6 frames at the earliest (index 5); one frame of slack for a frame segmented differently
    assert confirmed_at is not None and confirmed_at <= 6, confirmed_at
