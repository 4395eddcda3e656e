"""Fast mode's drawn detections and tracker state are what their slow forms give."""

from __future__ import annotations

from collections import deque

import numpy as np

from citysim.config.kinds import DETECTOR_CLASSES
from citysim.fast.drawn import DRAWN_P_TARGET, SensedTracker, drawn_detection
from detector.detector import Detection


def test_a_drawn_detection_is_the_one_the_constructor_makes():
    for cls in DETECTOR_CLASSES:
        fast = drawn_detection([3, 4, 5, 6], 12.5, cls, -2)
        probabilities = np.array([1.0 - DRAWN_P_TARGET if c == "noise" else 0.0 for c in DETECTOR_CLASSES])
        probabilities[DETECTOR_CLASSES.index(cls)] += DRAWN_P_TARGET if cls != "noise" else 0.0
        slow = Detection((3, 4, 5, 6), np.array([0.0, 0.0, 0.0, 12.5, 0.0, 0.0]), cls, probabilities, DRAWN_P_TARGET,
                         -2)  # fmt: skip
        assert vars(fast).keys() == vars(slow).keys()
        for name, value in vars(slow).items():
            got = getattr(fast, name)
            assert np.array_equal(got, value) if isinstance(value, np.ndarray) else got == value, name
    a, b = drawn_detection((0, 0, 1, 1), 1.0, "vehicle", 1), drawn_detection((0, 0, 1, 1), 1.0, "vehicle", 2)
    assert a.probabilities is not b.probabilities  # each its own array


class _DequeTracker:
    """``SensedTracker`` as it was: a deque of the last n hits per track."""

    def __init__(self, k=2, n=6, max_missed=3):
        self.k, self.n, self.max_missed, self.history = k, n, max_missed, {}

    def update(self, frame_k, track_id, hit):
        last_k, hist = self.history.get(track_id, (None, None))
        if hist is None or frame_k - last_k > self.max_missed + 1:
            hist = deque(maxlen=self.n)
        hist.append(hit)
        self.history[track_id] = (frame_k, hist)

    def is_confirmed(self, track_id):
        entry = self.history.get(track_id)
        return entry is not None and sum(entry[1]) >= self.k


def test_the_trackers_bits_confirm_as_the_last_n_hits_did():
    rng = np.random.default_rng(2)
    fast, slow = SensedTracker(), _DequeTracker()
    confirmed = 0
    for frame_k in range(5000):
        for track_id in range(6):
            if rng.random() < 0.6:
                hit = bool(rng.random() < 0.3)
                fast.update(frame_k, track_id, hit)
                slow.update(frame_k, track_id, hit)
        for track_id in range(7):
            assert fast.is_confirmed(track_id) == slow.is_confirmed(track_id)
            confirmed += fast.is_confirmed(track_id)
    assert 0 < confirmed < 5000 * 6
