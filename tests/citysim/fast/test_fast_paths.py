"""Fast mode's batched and trimmed paths leave the state their one-at-a-time forms left, bit for bit."""

from __future__ import annotations

import numpy as np

from citysim.fast.drawn import SensedTracker


def test_a_frames_updates_at_once_leave_the_tracker_as_one_by_one():
    rng = np.random.default_rng(7)
    one, batch = SensedTracker(), SensedTracker()
    for frame_k in range(3000):
        # many tracks, so the history passes 256 and is pruned mid-frame; some come back after gaps
        ids = sorted({int(t) for t in rng.integers(0, 400, int(rng.integers(0, 12)))})
        hits = [bool(rng.random() < 0.4) for _ in ids]
        for track_id, hit in zip(ids, hits, strict=True):
            one.update(frame_k, track_id, hit)
        batch.update_all(frame_k, ids, hits)
        assert batch.history == one.history
        assert list(batch.history) == list(one.history)  # the same order, so the same pruning later
