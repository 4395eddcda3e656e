"""The detections and tracker state fast mode's detector stand-in (``citysim.fast.sensors``) hands out.

``drawn_detection`` builds a ``detector.detector.Detection`` for a drawn hit; ``SensedTracker``
keeps the k-of-n state the real detector's light box tracker would.
"""

from __future__ import annotations

import numpy as np

from citysim.config.kinds import DETECTOR_CLASSES
from detector.detector import NO_TRACK_FIELDS, Detection, detection_from_fields

#: The p_target a drawn target detection carries (above any usual threshold), and a missed one's.
DRAWN_P_TARGET = 0.9


class SensedTracker:
    """Per track, the last n frames' hits; confirmed at k of them (``detector.confirm.Tracker``'s
    defaults: 2 of 6). A track unseen for more than 3 frames starts over, as a dropped one would.
    The hits are kept as the low n bits of an int (the latest the lowest): told every drawn
    candidate's every frame, a deque per track cost more than the draw."""

    def __init__(self, k: int = 2, n: int = 6, max_missed_frames: int = 3):
        self.k, self.n, self.max_missed = k, n, max_missed_frames
        self.mask = (1 << n) - 1
        self.history: dict[int, tuple[int, int]] = {}  # track -> (last frame, hit bits)

    def update(self, frame_k: int, track_id: int, hit: bool) -> None:
        """Frame ``frame_k``'s draw of one track (a false-alarm episode's)."""
        self.update_all(frame_k, [track_id], [hit])

    def update_all(self, frame_k: int, track_ids: list[int], hits: list[bool]) -> None:
        """Frame ``frame_k``'s draws of tracks ``track_ids`` (``hits``), in turn, in one call (a frame's
        candidates): a track unseen for more than ``max_missed`` frames starts over."""
        history, mask, gap = self.history, self.mask, self.max_missed + 1
        for track_id, hit in zip(track_ids, hits, strict=True):
            last_k, bits = history.get(track_id, (None, 0))
            if last_k is None or frame_k - last_k > gap:
                bits = 0
            history[track_id] = (frame_k, ((bits << 1) | bool(hit)) & mask)
            if len(history) > 256:  # forget tracks long gone
                history = self.history = {t: v for t, v in history.items() if frame_k - v[0] <= gap}

    def is_confirmed(self, track_id: int) -> bool:
        entry = self.history.get(track_id)
        return entry is not None and entry[1].bit_count() >= self.k


def drawn_detection(box_px, distance_m: float, cls: str, track_id: int) -> Detection:
    """A drawn Detection: what ``Detection(box, features, cls, probabilities, DRAWN_P_TARGET,
    track_id)`` makes (its other fields their defaults), built as ``detector.detector`` builds its
    own (the frozen dataclass's ``__init__`` cost several times this)."""
    return detection_from_fields({
        "box_px": tuple(box_px), "features": np.array([0.0, 0.0, 0.0, distance_m, 0.0, 0.0]), "cls": cls,
        "probabilities": _DRAWN_PROBABILITIES[cls].copy(), "p_target": DRAWN_P_TARGET, "track_id": track_id,
        **NO_TRACK_FIELDS})  # fmt: skip


def _drawn_probabilities(cls: str) -> np.ndarray:
    """The class probabilities a detection drawn as ``cls`` carries: ``DRAWN_P_TARGET`` on its class."""
    probabilities = np.array([1.0 - DRAWN_P_TARGET if c == "noise" else 0.0 for c in DETECTOR_CLASSES])
    probabilities[DETECTOR_CLASSES.index(cls)] += DRAWN_P_TARGET if cls != "noise" else 0.0
    return probabilities


_DRAWN_PROBABILITIES = {cls: _drawn_probabilities(cls) for cls in DETECTOR_CLASSES}
