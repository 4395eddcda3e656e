"""Per-object figures with tracks (experiments.paper.tracks) on hand-made frames."""

from __future__ import annotations

import numpy as np
import pytest

from citysim.render.camera import TruthObject
from detector.classes import CLASSES
from detector.detector import Detection
from detector.segment import Regions
from experiments.paper.scenes import SceneRecords, score_frame
from experiments.paper.tracks import (
    MIN_OBJECT_FRAMES,
    all_track_figures,
    per_region_object_figures,
    track_figures,
)


def _truth(oid, cls, box):
    return TruthObject(oid, cls, *box, touches_border=False, fully_visible=True, distance_m=10.0)


def _det(box, p_target, track_id, target, reason=None):
    probs = np.full(len(CLASSES), p_target / (len(CLASSES) - 1))
    probs[0] = 1.0 - p_target
    return Detection(tuple(box), np.zeros(6), "pedestrian", probs, p_target, track_id, track_cls="pedestrian",
                     track_p_target=p_target, track_target=target, track_reason=None if target else reason)


def _regions():
    return Regions(np.zeros((0, 4), np.int32), np.zeros(0), [], np.zeros(0, bool), 0.0, np.zeros((240, 320), np.uint8))


def records() -> SceneRecords:
    """Six frames: walker 1 found by its track in frame 3; walker 2 always seen, never a target track;
    track 9 matches nothing and is a target once; track 10 lies on walker 1 (a piece) and is a target."""
    rec = SceneRecords()
    walker_1, walker_2 = (10, 10, 20, 50), (100, 10, 20, 50)
    for k in range(MIN_OBJECT_FRAMES + 1):
        truth = [_truth(1, "pedestrian", walker_1), _truth(2, "pedestrian", walker_2)]
        dets = [
            _det(walker_1, 0.9, 5, k >= 3),
            _det(walker_2, 0.8, 6, False, "erratic"),
            _det((250, 150, 10, 10), 0.7, 9, k == 2, "too few frames"),
            _det((12, 12, 16, 10), 0.6, 10, True),
        ]
        score_frame(rec, truth, dets, _regions(), 25.0, 320 * 240, ("X", 0), k)
    return rec


def test_objects_missed_and_noise_tracks_called_target():
    rec = records()
    run = track_figures(rec)
    assert (run.objects, run.object_miss) == (2, 0.5)  # walker 2's track never was a target
    assert (run.noise_tracks, run.track_fpr) == (2, 1.0)  # tracks 9 and 10 both were, at least once
    assert (run.clean_noise_tracks, run.clean_track_fpr) == (1, 1.0)  # track 10 lies on walker 1
    # rows: 12 target rows, 3 of them target (walker 1, frames 3-5); 12 noise rows, 1 + 6 target
    assert run.frame_fnr == pytest.approx(9 / 12) and run.frame_fpr == pytest.approx(7 / 12)
    # each frame's own P(target) >= 0.5 calls every row a target: nothing missed, every noise track a target
    frames = per_region_object_figures(rec)
    assert (frames.object_miss, frames.track_fpr, frames.frame_fnr) == (0.0, 1.0, 0.0)


def test_poolings_recompute_decisions_with_the_runs_plausibility():
    rec = records()
    figures = all_track_figures(rec)
    # every detection's own P(target) >= 0.5, so any pooling calls a track a target wherever the run
    # found it plausible: walker 1 from frame 0 (the run: from frame 3), walker 2 never (erratic),
    # track 9 in frame 2 only
    for name in ("mean_log", "mean", "last"):
        f = figures[name]
        assert (f.object_miss, f.clean_noise_tracks, f.clean_track_fpr) == (0.5, 1, 1.0), name
        assert f.frame_fnr == pytest.approx(6 / 12), name
    with pytest.raises(ValueError, match="decision: must be"):
        track_figures(rec, "median")
