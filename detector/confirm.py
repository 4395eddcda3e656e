"""Decisions over several frames: the paper's eq. 12, k-of-n confirmation and a light tracker.

A single frame's classification is noisy (the paper's night true-positive rate
is 0.76 per frame). Its section 8 proposes deciding over a window of frames
(eq. 12, a Bernoulli scheme) and tracking objects so that the frames of one
window belong to one object. Here:

* ``p_detect_within(p, n)``: eq. 12, the probability that an object detected
  with per-frame probability ``p`` is detected in more than half of ``n`` frames.
* ``KOfNConfirmer``: a lamp-level switch, on when ``k`` of the last ``n``
  frames held a target (the paper's implementation uses 2 of 6).
* ``Tracker``: greedy association of boxes across frames by IoU and centroid
  distance with a constant-velocity prediction; each track keeps the last
  ``n`` per-frame target decisions and is confirmed when ``k`` of them are hits.

Boxes are OpenCV ``(x, y, w, h)`` pixel tuples; velocities are px per frame.
"""

from __future__ import annotations

import math
import numbers

import numpy as np


def p_detect_within(p: float, n: int) -> float:
    """Eq. 12: P(at least floor(n/2) + 1 successes in n Bernoulli trials of probability p)."""
    if isinstance(p, bool) or not isinstance(p, numbers.Real) or not (0.0 <= float(p) <= 1.0):
        raise ValueError(f"p_detect_within: p is a per-frame probability in [0, 1], got {p!r}")
    if isinstance(n, bool) or not isinstance(n, numbers.Integral) or n < 1:
        raise ValueError(f"p_detect_within: n is a number of frames, an integer >= 1, got {n!r}")
    p, n = float(p), int(n)
    q = 1.0 - p
    return float(sum(math.comb(n, k) * p**k * q ** (n - k) for k in range(n // 2 + 1, n + 1)))


def _check_k_of_n(owner: str, k: int, n: int) -> None:
    for name, value in (("n", n), ("k", k)):
        if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
            raise ValueError(f"{owner}: {name} must be an integer >= 1, got {value!r}")
    if k > n:
        raise ValueError(f"{owner}: k must be <= n (k of the last n frames), got k={k}, n={n}")


class KOfNConfirmer:
    """True while at least ``k`` of the last ``n`` frames were hits (fewer than n frames seen count as misses)."""

    def __init__(self, k: int = 2, n: int = 6) -> None:
        _check_k_of_n("KOfNConfirmer", k, n)
        self.k, self.n = int(k), int(n)
        self._window = np.zeros(self.n, dtype=bool)
        self._next = 0

    def update(self, hit: bool) -> bool:
        """Record one frame's decision; return whether the target is now confirmed."""
        self._window[self._next] = bool(hit)
        self._next = (self._next + 1) % self.n
        return self.confirmed

    @property
    def confirmed(self) -> bool:
        return int(np.count_nonzero(self._window)) >= self.k

    @property
    def hits(self) -> int:
        """Hits among the last n frames."""
        return int(np.count_nonzero(self._window))

    def reset(self) -> None:
        self._window[:] = False
        self._next = 0


def box_iou(a_px: np.ndarray, b_px: np.ndarray) -> np.ndarray:
    """IoU matrix (A, B) of two sets of (x, y, w, h) boxes (pixel-area convention: a box covers w x h pixels)."""
    a = np.asarray(a_px, np.float64).reshape(-1, 4)
    b = np.asarray(b_px, np.float64).reshape(-1, 4)
    lo = np.maximum(a[:, None, :2], b[None, :, :2])
    hi = np.minimum(a[:, None, :2] + a[:, None, 2:], b[None, :, :2] + b[None, :, 2:])
    wh = np.clip(hi - lo, 0.0, None)
    inter = wh[..., 0] * wh[..., 1]
    union = (a[:, 2] * a[:, 3])[:, None] + b[:, 2] * b[:, 3] - inter
    return np.divide(inter, union, out=np.zeros_like(inter), where=union > 0)


class Tracker:
    """Associates each frame's boxes with tracks; ids are ints from 1, never reused.

    Matching is greedy on ``IoU + max(0, 1 - d / max_distance_diag)`` between
    each track's predicted box (last box moved by its velocity) and the new
    boxes, where d is the centroid distance in units of the predicted box's
    diagonal. A pair may match when its IoU is at least ``min_iou`` or d is at
    most ``max_distance_diag``. A track unseen for more than
    ``max_missed_frames`` frames is dropped. ``velocity_smoothing`` in (0, 1]
    is the weight of the newest displacement in the velocity estimate.
    """

    def __init__(
        self,
        max_missed_frames: int = 3,
        min_iou: float = 0.1,
        max_distance_diag: float = 1.0,
        velocity_smoothing: float = 0.5,
        confirm_k: int = 2,
        confirm_n: int = 6,
    ) -> None:
        if (
            isinstance(max_missed_frames, bool)
            or not isinstance(max_missed_frames, numbers.Integral)
            or max_missed_frames < 0
        ):
            raise ValueError(
                f"Tracker: max_missed_frames must be an integer >= 0, got {max_missed_frames!r}"
            )
        if not 0.0 <= min_iou <= 1.0:
            raise ValueError(f"Tracker: min_iou must be in [0, 1], got {min_iou!r}")
        if not max_distance_diag >= 0.0:
            raise ValueError(
                f"Tracker: max_distance_diag must be >= 0 (box diagonals), got {max_distance_diag!r}"
            )
        if not 0.0 < velocity_smoothing <= 1.0:
            raise ValueError(
                f"Tracker: velocity_smoothing must be in (0, 1], got {velocity_smoothing!r}"
            )
        _check_k_of_n("Tracker", confirm_k, confirm_n)
        self.max_missed_frames = int(max_missed_frames)
        self.min_iou = float(min_iou)
        self.max_distance_diag = float(max_distance_diag)
        self.velocity_smoothing = float(velocity_smoothing)
        self.confirm_k, self.confirm_n = int(confirm_k), int(confirm_n)
        self.reset()

    def reset(self) -> None:
        """Forget every track (ids keep counting up, so an old id never comes back)."""
        self.ids = np.zeros(0, np.int64)
        self.boxes_px = np.zeros((0, 4))  # last observed box per track
        self.velocities_px = np.zeros((0, 2))  # px per frame
        self.missed = np.zeros(0, np.int64)  # frames since last seen
        self.sightings = np.zeros(0, np.int64)  # frames in which the track was matched
        # the last n target decisions per track as bits, newest in bit 0
        self.history_bits = np.zeros(0, np.uint64)
        if not hasattr(self, "_next_id"):
            self._next_id = 1

    def __len__(self) -> int:
        return len(self.ids)

    @property
    def confirmed(self) -> np.ndarray:
        """(T,) bool: tracks with at least k target frames among their last n."""
        return np.bitwise_count(self.history_bits) >= self.confirm_k

    def confirmed_ids(self) -> set[int]:
        return {int(i) for i in self.ids[self.confirmed]}

    def is_confirmed(self, track_id: int) -> bool:
        return track_id in self.confirmed_ids()

    def predicted_boxes_px(self) -> np.ndarray:
        """(T, 4) where each track is expected in the next frame."""
        out = self.boxes_px.copy()
        out[:, :2] += self.velocities_px * (self.missed + 1)[:, None]
        return out

    def _match(self, boxes: np.ndarray) -> np.ndarray:
        """Greedy assignment: (N,) index of each box's track, -1 for none."""
        t, n = len(self.ids), len(boxes)
        track_of = np.full(n, -1, np.intp)
        if t == 0 or n == 0:
            return track_of
        pred = self.predicted_boxes_px()
        iou = box_iou(pred, boxes)
        gap = (pred[:, None, :2] + pred[:, None, 2:] / 2) - (
            boxes[None, :, :2] + boxes[None, :, 2:] / 2
        )
        diag = np.maximum(np.hypot(pred[:, 2], pred[:, 3]), 1.0)
        dist = np.hypot(gap[..., 0], gap[..., 1]) / diag[:, None]
        score = iou + np.clip(1.0 - dist / max(self.max_distance_diag, 1e-9), 0.0, None)
        score[(iou < self.min_iou) & (dist > self.max_distance_diag)] = -np.inf
        for _ in range(min(t, n)):
            flat = int(np.argmax(score))
            ti, di = divmod(flat, n)
            if score[ti, di] == -np.inf:
                break
            track_of[di] = ti
            score[ti, :] = -np.inf
            score[:, di] = -np.inf
        return track_of

    def update(self, boxes_px: np.ndarray, is_target: np.ndarray | None = None) -> np.ndarray:
        """Associate this frame's (N, 4) boxes; return their (N,) track ids.

        ``is_target`` (N,) bool is each box's classification in this frame
        (all False if omitted); it feeds the per-track k-of-n confirmation.
        A frame in which a track is not seen counts as a miss.
        """
        boxes = np.asarray(boxes_px, np.float64).reshape(-1, 4)
        n = len(boxes)
        hits = np.zeros(n, bool) if is_target is None else np.asarray(is_target, bool).reshape(-1)
        if len(hits) != n:
            raise ValueError(f"Tracker.update: is_target has {len(hits)} entries for {n} boxes")
        track_of = self._match(boxes)
        matched = track_of >= 0
        ti, di = track_of[matched], np.flatnonzero(matched)

        self.history_bits = (self.history_bits << np.uint64(1)) & np.uint64(
            (1 << self.confirm_n) - 1
        )
        self.missed += 1
        if len(ti):
            # velocity from the displacement since the track was last seen
            step = (boxes[di, :2] + boxes[di, 2:] / 2) - (
                self.boxes_px[ti, :2] + self.boxes_px[ti, 2:] / 2
            )
            step /= self.missed[ti][:, None]
            a = self.velocity_smoothing
            # a track seen once has no velocity yet: take its first displacement whole
            first = (self.sightings[ti] == 1)[:, None]
            self.velocities_px[ti] = np.where(
                first, step, a * step + (1 - a) * self.velocities_px[ti]
            )
            self.sightings[ti] += 1
            self.boxes_px[ti] = boxes[di]
            self.missed[ti] = 0
            self.history_bits[ti] |= hits[di].astype(np.uint64)

        ids_out = np.empty(n, np.int64)
        ids_out[di] = self.ids[ti]
        new = np.flatnonzero(~matched)
        expired = self.missed > self.max_missed_frames
        if len(new) == 0 and not expired.any():
            return ids_out
        # unmatched boxes start tracks; long-unseen tracks end
        new_ids = np.arange(self._next_id, self._next_id + len(new), dtype=np.int64)
        self._next_id += len(new)
        ids_out[new] = new_ids
        keep = ~expired
        self.ids = np.concatenate([self.ids[keep], new_ids])
        self.boxes_px = np.concatenate([self.boxes_px[keep], boxes[new]])
        self.velocities_px = np.concatenate([self.velocities_px[keep], np.zeros((len(new), 2))])
        self.missed = np.concatenate([self.missed[keep], np.zeros(len(new), np.int64)])
        self.sightings = np.concatenate([self.sightings[keep], np.ones(len(new), np.int64)])
        self.history_bits = np.concatenate([self.history_bits[keep], hits[new].astype(np.uint64)])
        return ids_out
