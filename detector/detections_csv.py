"""What ``python -m detector`` writes per region and per track: detections.csv and tracks.csv.

One answer per region: ``target`` (1/0) is what a lamp would act on: the track's decision
where the region is on a track (``Detection.track_target``), else the region's own P(target)
against the threshold; ``target_cls`` is the class of that decision ('noise' when it is no
target). The per-frame classifier's output, which a lamp does not act on, is in the columns
named ``frame_cls`` and ``frame_p_target``. summary.json's counts are counted from these rows.
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from pathlib import Path

#: detections.csv's columns: the decision first, then the per-frame classifier, the region's
#: size on the ground (m), its track and where it stands on the ground
CSV_HEADER = ["frame", "x", "y", "w", "h", "target", "target_cls", "frame_cls", "frame_p_target", "width_m",
              "height_m", "area_m2", "distance_m", "track_id", "track_p_target", "ground_x_m", "ground_y_m",
              "speed_mps"]

TRACKS_HEADER = ["track_id", "first_frame", "last_frame", "frames_seen", "cls", "target_frames", "mean_speed_mps",
                 "reject_reason", "merged_into"]


def decision(det, threshold: float) -> tuple[bool, str]:
    """(is the detection a target, its class or 'noise'): the track's decision where it has a
    track, else its own frame's P(target) against ``threshold``."""
    if det.track_p_target is not None:
        return bool(det.track_target), det.track_cls if det.track_target else "noise"
    if det.p_target >= threshold:
        return True, det.cls
    return False, "noise"


def fixed(value: float | None, digits: int) -> str:
    """A number with ``digits`` decimals, or an empty cell for None (not known yet)."""
    return "" if value is None else f"{value:.{digits}f}"


class DetectionRows:
    """Writes detections.csv row by row and counts what it wrote (for summary.json)."""

    def __init__(self, fh, threshold: float) -> None:
        self._rows = csv.writer(fh)
        self._rows.writerow(CSV_HEADER)
        self.threshold = threshold
        self.frames_with_target = 0
        self.target_rows_per_class: dict[str, int] = {}
        self.frame_cls_rows: dict[str, int] = {}

    def write_frame(self, frame: int, detections: Sequence, boxes_px: Sequence[tuple[int, int, int, int]]) -> list:
        """Write one frame's rows (``boxes_px``: each detection's box in the video's pixels);
        returns each detection's (target, target_cls)."""
        decisions = [decision(det, self.threshold) for det in detections]
        for det, (x, y, w, h), (target, target_cls) in zip(detections, boxes_px, decisions, strict=True):
            wm, hm, am, dm = det.features[:4]
            self._rows.writerow([frame, x, y, w, h, int(target), target_cls, det.cls, f"{det.p_target:.4f}",
                                 f"{wm:.3f}", f"{hm:.3f}", f"{am:.3f}", f"{dm:.3f}", det.track_id,
                                 fixed(det.track_p_target, 4), fixed(det.ground_x_m, 3), fixed(det.ground_y_m, 3),
                                 fixed(det.speed_mps, 3)])
            self.frame_cls_rows[det.cls] = self.frame_cls_rows.get(det.cls, 0) + 1
            if target:
                self.target_rows_per_class[target_cls] = self.target_rows_per_class.get(target_cls, 0) + 1
        self.frames_with_target += any(t for t, _ in decisions)
        return decisions

    def counts(self) -> dict:
        """summary.json's counts: each is a count of detections.csv's rows."""
        return {"frames_with_target": self.frames_with_target,
                "target_rows_per_class": dict(sorted(self.target_rows_per_class.items())),
                "frame_cls_rows_per_class": dict(sorted(self.frame_cls_rows.items()))}


def write_tracks_csv(tracks, path: Path) -> dict[str, int]:
    """One row per track of the video (``detector.tracks``), by id; returns tracks per class.

    ``cls`` is the class the track had most often while it was a target, 'noise' if it never
    was one; ``reject_reason`` then says why (the reason of most of its frames);
    ``merged_into`` names the track it was joined to as a fragment.
    """
    counts: dict[str, int] = {}
    with open(path, "w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(TRACKS_HEADER)
        for t in sorted([*tracks.ended, *tracks.tracks], key=lambda t: t.track_id):
            cls = max(t.target_classes, key=t.target_classes.get) if t.target_classes else "noise"
            reason = "" if t.target_classes else max(t.reasons, key=t.reasons.get, default="")
            out.writerow([t.track_id, t.first_frame, t.last_frame, t.sightings, cls, t.target_frames,
                          fixed(t.mean_speed_mps, 3), reason, "" if t.merged_into is None else t.merged_into])
            counts[cls] = counts.get(cls, 0) + 1
    return counts
