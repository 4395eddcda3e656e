"""Per-object figures with the detector's tracks, beside the per-region ones.

Three ways of counting, all from one filming (``experiments.paper.scenes``):

* **frames, track decision**: the same rows as the 'objects' variant (every detection and
  every missed eligible target, per frame), decided by the detection's track (plausible and
  pooled P(target) >= 0.5) instead of its own frame's P(target);
* **per object** (what a lamp owes a road user): a target object (scene, camera, object) is
  *missed* when no detection matched to it (IoU >= 0.3) was a target track in any of its
  eligible frames; objects eligible in fewer than ``MIN_OBJECT_FRAMES`` frames are left out
  (a glimpse at the edge of range is no crossing);
* **per noise track**: a track whose detections mostly match no target (noise, animals,
  insects, light) is a *false positive* when it was a target track in any frame; *clean*
  leaves out the noise tracks whose rows mostly lie on a target's box (``fragment``: a piece
  of a road user, or two merged, that IoU matching cannot give to one object), as the
  'regions, fragments out' variant does for rows.

Pooling alternatives (``detector.tracks.track.POOLINGS``) are computed from the same rows:
each row's track pooled over its last ``POOL_FRAMES`` scored rows, decided with the run's
plausibility (which does not depend on the pooling). The run's own pooling is ``mean_log``;
its offline figure differs from the run's decisions only in a track's first frames after
the background warm-up (frames before it are not scored rows).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from detector.classes import CLASSES
from detector.tracks.track import POOL_FRAMES, POOLINGS, pool_probabilities
from experiments.paper.scenes import TARGET_THRESHOLD, SceneRecords

MIN_OBJECT_FRAMES = 5
_NOISE = CLASSES.index("noise")


@dataclass(frozen=True)
class TrackFigures:
    """One condition's figures for one way of deciding (see the module docstring)."""

    decision: str  # 'run' (the detector's own track decisions) or a pooling name
    frame_fnr: float | None
    frame_fpr: float | None
    objects: int
    object_miss: float | None
    noise_tracks: int
    track_fpr: float | None
    clean_noise_tracks: int
    clean_track_fpr: float | None


def _share(mask) -> float | None:
    mask = np.asarray(mask, dtype=bool)
    return float(mask.mean()) if mask.size else None


def pooled_decisions(records: SceneRecords, pooling: str) -> np.ndarray:
    """Each row's track decision recomputed with ``pooling`` (missed rows: False)."""
    windows: dict = {}
    out = np.zeros(len(records.truth_cls), dtype=bool)
    for i, (track, plausible) in enumerate(zip(records.row_track, records.row_plausible, strict=True)):
        if track is None:
            continue
        window = windows.setdefault(track, deque(maxlen=POOL_FRAMES))
        window.append(records.probabilities[i].tolist())
        pooled = pool_probabilities(window, pooling)
        out[i] = plausible and 1.0 - pooled[_NOISE] >= TARGET_THRESHOLD
    return out


def track_figures(records: SceneRecords, decision: str = "run") -> TrackFigures:
    """The three counts for the run's decisions or a pooling's (``POOLINGS``)."""
    if decision == "run":
        target = np.asarray(records.row_track_target, dtype=bool)
    elif decision in POOLINGS:
        target = pooled_decisions(records, decision)
    else:
        raise ValueError(f"decision: must be 'run' or one of {POOLINGS}, got {decision!r}")
    return figures_of(records, decision, target)


def figures_of(records: SceneRecords, decision: str, target: np.ndarray) -> TrackFigures:
    """The three counts for per-row target decisions ``target`` (missed rows False)."""
    truth_target = np.asarray(records.truth_cls, dtype=object) != "noise"
    misses = [
        not any(r >= 0 and target[r] for r in rows)
        for rows in records.object_rows.values()
        if len(rows) >= MIN_OBJECT_FRAMES
    ]
    fragment = np.asarray(records.fragment, dtype=bool)
    by_track: dict = {}
    for i, track in enumerate(records.row_track):
        if track is not None:
            noise_rows, fragments, rows, hit = by_track.get(track, (0, 0, 0, False))
            by_track[track] = (noise_rows + (not truth_target[i]), fragments + fragment[i], rows + 1,
                               hit or bool(target[i]))  # fmt: skip
    noise = [(hit, 2 * fragments >= rows) for noise_rows, fragments, rows, hit in by_track.values()
             if 2 * noise_rows > rows]  # fmt: skip
    clean = [hit for hit, on_target in noise if not on_target]
    return TrackFigures(
        decision,
        _share(~target[truth_target]),
        _share(target[~truth_target]),
        len(misses),
        _share(misses),
        len(noise),
        _share([hit for hit, _ in noise]),
        len(clean),
        _share(clean),
    )


def all_track_figures(records: SceneRecords) -> dict[str, TrackFigures]:
    """The run's decisions and every pooling's, by name."""
    return {name: track_figures(records, name) for name in ("run", *POOLINGS)}


def per_region_object_figures(records: SceneRecords) -> TrackFigures:
    """The per-object and per-track counts with each frame's own decision (P(target) >= 0.5):
    what the tracks are compared with (tracks still group the rows of a noise object)."""
    p_target = 1.0 - records.probability_matrix[:, _NOISE] if records.probabilities else np.zeros(0)
    detected = np.asarray(records.detected, dtype=bool)
    return figures_of(records, "per frame", detected & (p_target >= TARGET_THRESHOLD))
