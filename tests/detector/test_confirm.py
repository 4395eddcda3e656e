"""Eq. 12, k-of-n confirmation and the tracker."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from detector.confirm import KOfNConfirmer, Tracker, box_iou, p_detect_within


# -------------------------------------------------------------------- eq. 12
def test_paper_figure_076_over_five_frames_is_0907():
    # section 8.1: a per-frame rate of 0.76 becomes 0.90 over five frames
    assert round(p_detect_within(0.76, 5), 3) == 0.907


@pytest.mark.parametrize("p, n", [(0.3, 1), (0.76, 4), (0.6, 6), (0.9, 7), (0.5, 5)])
def test_eq12_equals_counting_every_outcome(p, n):
    brute = sum(
        np.prod([p if hit else 1 - p for hit in outcome])
        for outcome in itertools.product([False, True], repeat=n)
        if sum(outcome) > n / 2
    )
    assert p_detect_within(p, n) == pytest.approx(brute, abs=1e-12)


def test_eq12_grows_with_n_only_above_one_half():
    odd = [1, 3, 5, 7, 9]
    up = [p_detect_within(0.7, n) for n in odd]
    down = [p_detect_within(0.3, n) for n in odd]
    assert all(a < b for a, b in zip(up, up[1:], strict=False))
    assert all(a > b for a, b in zip(down, down[1:], strict=False))
    assert p_detect_within(0.0, 5) == 0.0 and p_detect_within(1.0, 5) == 1.0


@pytest.mark.parametrize(
    "p, n, field", [(1.2, 5, "p"), (-0.1, 5, "p"), (True, 5, "p"), (0.5, 0, "n"), (0.5, 2.5, "n")]
)
def test_eq12_rejects_bad_arguments(p, n, field):
    with pytest.raises(ValueError, match=rf"\b{field} is"):
        p_detect_within(p, n)


# --------------------------------------------------------------------- k of n
def test_two_of_six_switches_on_and_off_with_the_window():
    conf = KOfNConfirmer()  # the paper implementation's 2 of 6
    hits = [1, 0, 0, 0, 1, 0, 1, 0, 0, 0, 0, 0, 0]
    states = [conf.update(bool(h)) for h in hits]
    # on at the 2nd hit (frame 4); frame 6 drops frame 0 but adds a hit; off at frame 10,
    # whose window (frames 5-10) holds only the hit of frame 6
    assert states == [
        False,
        False,
        False,
        False,
        True,
        True,
        True,
        True,
        True,
        True,
        False,
        False,
        False,
    ]
    conf.reset()
    assert not conf.confirmed and conf.hits == 0


def test_k_of_n_validates_its_window():
    with pytest.raises(ValueError, match="k must be <= n"):
        KOfNConfirmer(k=7, n=6)
    with pytest.raises(ValueError, match="n must be an integer"):
        KOfNConfirmer(k=1, n=0)


# -------------------------------------------------------------------- tracker
def test_box_iou_by_hand():
    a = np.array([[0, 0, 10, 10]])
    b = np.array([[5, 0, 10, 10], [20, 20, 5, 5], [0, 0, 10, 10]])
    np.testing.assert_allclose(box_iou(a, b), [[50 / 150, 0.0, 1.0]])


def crossing_boxes(frame: int) -> np.ndarray:
    """A walks right, B walks left, one row apart: they overlap around frame 20."""
    return np.array([[20 + 5 * frame, 100, 20, 50], [220 - 5 * frame, 106, 22, 46]], float)


def test_tracker_keeps_ids_of_two_crossing_objects():
    tracker = Tracker()
    seen = []
    for f in range(40):
        boxes = crossing_boxes(f)
        order = [1, 0] if f % 3 == 0 else [0, 1]  # detection order must not matter
        ids = tracker.update(boxes[order], np.array([True, False])[order])
        seen.append(ids[np.argsort(order)])
    seen = np.array(seen)
    assert len(set(seen[:, 0])) == 1 and len(set(seen[:, 1])) == 1
    assert seen[0, 0] != seen[0, 1]
    # A was a target every frame, B never
    a_id, b_id = int(seen[0, 0]), int(seen[0, 1])
    assert tracker.is_confirmed(a_id) and not tracker.is_confirmed(b_id)


def test_tracker_learns_velocities():
    # at the crossing A and B stand at one place; their velocities are what tells them apart
    tracker = Tracker()
    for f in range(10):
        tracker.update(crossing_boxes(f))
    order = np.argsort(tracker.ids)
    np.testing.assert_allclose(tracker.velocities_px[order], [[5, 0], [-5, 0]], atol=1e-9)


def test_tracks_survive_short_gaps_and_expire_after_long_ones():
    tracker = Tracker(max_missed_frames=3)
    box = np.array([[100, 100, 20, 40]], float)
    first = tracker.update(box)[0]
    tracker.update(box + [4, 0, 0, 0])
    for _ in range(3):  # missed three frames: still alive, predicted forward
        tracker.update(np.zeros((0, 4)))
    assert first in tracker.ids
    again = tracker.update(box + [20, 0, 0, 0])[0]
    assert again == first
    for _ in range(4):
        tracker.update(np.zeros((0, 4)))
    assert len(tracker) == 0
    later = tracker.update(box)[0]
    assert later > first  # ids are never reused


def test_per_track_confirmation_is_k_of_last_n_frames():
    tracker = Tracker(confirm_k=2, confirm_n=6)
    box = np.array([[50, 50, 20, 40]], float)
    pattern = [True, False, False, False, False, True, False, False, False, False, False]
    states = []
    for f, hit in enumerate(pattern):
        (tid,) = tracker.update(box + [2 * f, 0, 0, 0], [hit])
        states.append(tracker.is_confirmed(int(tid)))
    # hits at frames 0 and 5 are 6 frames apart: both in the window only at frame 5
    assert states == [False] * 5 + [True] + [False] * 5


def test_tracker_validates_inputs():
    with pytest.raises(ValueError, match="is_target has 1 entries for 2 boxes"):
        Tracker().update(np.zeros((2, 4)), [True])
    with pytest.raises(ValueError, match="max_missed_frames"):
        Tracker(max_missed_frames=-1)
    with pytest.raises(ValueError, match="k must be <= n"):
        Tracker(confirm_k=4, confirm_n=3)


def test_plain_python_and_vectorised_pair_scores_agree():
    # boxes scattered around the predictions: near, touching, overlapping and far pairs
    rng = np.random.default_rng(11)
    tracker = Tracker(min_iou=0.1, max_distance_diag=1.0)
    for _ in range(50):
        pred = np.column_stack([rng.uniform(0, 100, (6, 2)), rng.uniform(2, 30, (6, 2))]).tolist()
        boxes = np.column_stack([rng.uniform(0, 100, (7, 2)), rng.uniform(2, 30, (7, 2))]).tolist()
        plain = tracker._scores(pred, boxes)
        vectorised = tracker._scores_vectorised(pred, boxes)
        assert [(t, d) for _, t, d in plain] == [(t, d) for _, t, d in vectorised]
        np.testing.assert_allclose([s for s, *_ in plain], [s for s, *_ in vectorised], rtol=1e-12)
        assert 0 < len(plain) < 42  # some pairs allowed, some not


def test_plain_python_and_vectorised_tracking_give_the_same_ids():
    rng = np.random.default_rng(5)
    plain, vectorised = Tracker(), Tracker()
    plain.SCALAR_MAX_PAIRS, vectorised.SCALAR_MAX_PAIRS = 10**9, 0
    starts = rng.uniform(0, 300, (8, 2))
    speeds = rng.uniform(-6, 6, (8, 2))
    for f in range(120):
        visible = rng.random(8) < 0.8
        centres = starts[visible] + speeds[visible] * f + rng.normal(0, 2, (visible.sum(), 2))
        boxes = np.column_stack([centres, np.full((visible.sum(), 2), 20.0)])
        hits = rng.random(len(boxes)) < 0.5
        np.testing.assert_array_equal(plain.update(boxes, hits), vectorised.update(boxes, hits))
    np.testing.assert_array_equal(plain.ids, vectorised.ids)
    np.testing.assert_allclose(plain.velocities_px, vectorised.velocities_px)
    assert plain.confirmed_ids() == vectorised.confirmed_ids()
