"""A steep camera's still regions (ghosts: track_id None) in the controllers' per-track windows.

Should a scenario ever set a lamp's camera looking steeply down (``detector.tracks.footprint.
is_steep``, e.g. tilted 60 degrees), its detector reports the ground a car uncovered as still
regions on no track (``detector.ghosts``): track_id None, reason ``STILL_REASON``, but their own
per-frame class and P(target) as before (a ghost on a painted line looked like a pedestrian on the
car-park clip). The controllers' windows (``citysim.control.track_windows``) key detections by
track id, None being the one window of detections without a track; a ghost counted there would
add up frame by frame and light the lamp.
"""

from __future__ import annotations

import numpy as np

from citysim.control.track_windows import (
    TrackWindows,
    fragment_keys,
    frame_hit,
    keyed_marks,
    plausible_marks,
)
from detector.detector import NO_TRACK_FIELDS, Detection
from detector.tracks.tracker import STILL_REASON

THRESHOLD = 0.5


def detection(**fields) -> Detection:
    base = {**NO_TRACK_FIELDS, "box_px": (10, 10, 20, 40), "features": np.zeros(11), "cls": "pedestrian",
            "probabilities": np.array([0.1, 0.8, 0.05, 0.03, 0.02]), "p_target": 0.9, "track_id": None}  # fmt: skip
    return Detection(**{**base, **fields})


GHOST = detection(track_cls="noise", track_p_target=0.0, track_target=False, track_reason=STILL_REASON,
                  ground_x_m=7.0, ground_y_m=2.5)  # fmt: skip


def test_a_still_region_is_never_a_hit_whatever_its_own_class():
    assert frame_hit(GHOST, THRESHOLD) is False
    # the per-frame path's detections (no track, no reason) count by their own P(target) as before
    assert frame_hit(detection(), THRESHOLD) is True


def test_a_ghost_in_every_frame_confirms_nothing_beside_a_confirmed_track():
    window = TrackWindows(2, 6, full_window=True)
    walker = detection(track_id=3, track_cls="pedestrian", track_p_target=0.8, track_target=True,
                       ground_x_m=9.0, ground_y_m=0.0)  # fmt: skip
    confirmed = set()
    for _ in range(12):
        keys, marks = keyed_marks([GHOST, walker], THRESHOLD, window)
        assert keys == [None, 3]  # a ghost is no fragment of the walker's track, and no track
        confirmed = window.update(marks)
        assert None not in confirmed
    assert confirmed == {3}
    window = TrackWindows(2, 6)
    for _ in range(12):
        assert window.update(plausible_marks([GHOST], THRESHOLD)) == set()
    assert fragment_keys([GHOST], window) == [None]
