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

from detector.tracks.associate import greedy_assign


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

    A lamp's frame holds a handful of boxes and tracks, so the state lives in
    Python lists and pairs are scored in plain Python (numpy's per-call cost
    would be most of the work); past ``SCALAR_MAX_PAIRS`` pairs the scores are
    one vectorised computation. The array attributes (``ids``, ``boxes_px``,
    ``velocities_px``, ``missed``, ``sightings``, ``history_bits``) are
    snapshots built on access.
    """

    #: up to this many track x box pairs are scored in plain Python
    SCALAR_MAX_PAIRS = 64

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
        self._window_mask = (1 << self.confirm_n) - 1
        self.reset()

    def reset(self) -> None:
        """Forget every track (ids keep counting up, so an old id never comes back)."""
        self._ids: list[int] = []
        self._boxes: list[list[float]] = []  # last observed (x, y, w, h) per track, px
        self._velocities: list[list[float]] = []  # px per frame
        self._missed: list[int] = []  # frames since last seen
        self._sightings: list[int] = []  # frames in which the track was matched
        # the last n target decisions per track as bits, newest in bit 0
        self._bits: list[int] = []
        if not hasattr(self, "_next_id"):
            self._next_id = 1

    def __len__(self) -> int:
        return len(self._ids)

    # ------------------------------------------------------------ snapshots
    @property
    def ids(self) -> np.ndarray:
        """(T,) int64 track ids."""
        return np.array(self._ids, np.int64)

    @property
    def boxes_px(self) -> np.ndarray:
        """(T, 4) last observed box per track."""
        return np.array(self._boxes, np.float64).reshape(-1, 4)

    @property
    def velocities_px(self) -> np.ndarray:
        """(T, 2) px per frame."""
        return np.array(self._velocities, np.float64).reshape(-1, 2)

    @property
    def missed(self) -> np.ndarray:
        """(T,) frames since each track was last seen."""
        return np.array(self._missed, np.int64)

    @property
    def sightings(self) -> np.ndarray:
        """(T,) frames in which each track was matched."""
        return np.array(self._sightings, np.int64)

    @property
    def history_bits(self) -> np.ndarray:
        """(T,) uint64: the last n target decisions, newest in bit 0."""
        return np.array(self._bits, np.uint64)

    @property
    def confirmed(self) -> np.ndarray:
        """(T,) bool: tracks with at least k target frames among their last n."""
        return np.array([b.bit_count() >= self.confirm_k for b in self._bits], bool)

    def confirmed_ids(self) -> set[int]:
        k = self.confirm_k
        return {i for i, b in zip(self._ids, self._bits, strict=True) if b.bit_count() >= k}

    def is_confirmed(self, track_id: int) -> bool:
        return track_id in self.confirmed_ids()

    def _predicted(self) -> list[tuple[float, float, float, float]]:
        return [
            (x + vx * (m + 1), y + vy * (m + 1), w, h)
            for (x, y, w, h), (vx, vy), m in zip(
                self._boxes, self._velocities, self._missed, strict=True
            )
        ]

    # ------------------------------------------------------------- matching
    def _scores(self, pred: list, boxes: list) -> list[tuple[float, int, int]]:
        """Allowed (score, track, box) pairs, in row-major order."""
        max_d = self.max_distance_diag
        max_d_floor = max(max_d, 1e-9)
        min_iou = self.min_iou
        # per box: corners, area, centre (conditional expressions: cheaper than min/max calls)
        extents = [
            (bx, by, bx + bw, by + bh, bw * bh, bx + bw / 2, by + bh / 2)
            for bx, by, bw, bh in boxes
        ]
        pairs = []
        for ti, (px, py, pw, ph) in enumerate(pred):
            p_right, p_bottom, p_area = px + pw, py + ph, pw * ph
            pcx, pcy = px + pw / 2, py + ph / 2
            diag = max(math.hypot(pw, ph), 1.0)
            for di, (bx, by, b_right, b_bottom, b_area, bcx, bcy) in enumerate(extents):
                dist = math.hypot(pcx - bcx, pcy - bcy) / diag
                iw = (p_right if p_right < b_right else b_right) - (px if px > bx else bx)
                ih = (p_bottom if p_bottom < b_bottom else b_bottom) - (py if py > by else by)
                if dist > max_d and min_iou > 0.0 and (iw <= 0.0 or ih <= 0.0):
                    continue  # far apart and no overlap: IoU 0 < min_iou
                inter = (iw if iw > 0.0 else 0.0) * (ih if ih > 0.0 else 0.0)
                union = p_area + b_area - inter
                iou = inter / union if union > 0 else 0.0
                if iou < min_iou and dist > max_d:
                    continue
                near = 1.0 - dist / max_d_floor
                pairs.append((iou + (near if near > 0.0 else 0.0), ti, di))
        return pairs

    def _scores_vectorised(self, pred: list, boxes: list) -> list[tuple[float, int, int]]:
        """``_scores`` for many pairs: one numpy computation over the (T, N) matrix."""
        p = np.array(pred, np.float64)
        b = np.array(boxes, np.float64)
        iou = box_iou(p, b)
        gap = (p[:, None, :2] + p[:, None, 2:] / 2) - (b[None, :, :2] + b[None, :, 2:] / 2)
        diag = np.maximum(np.hypot(p[:, 2], p[:, 3]), 1.0)
        dist = np.hypot(gap[..., 0], gap[..., 1]) / diag[:, None]
        score = iou + np.clip(1.0 - dist / max(self.max_distance_diag, 1e-9), 0.0, None)
        ti, di = np.nonzero((iou >= self.min_iou) | (dist <= self.max_distance_diag))
        return list(zip(score[ti, di].tolist(), ti.tolist(), di.tolist(), strict=True))

    def _match(self, boxes: list) -> list[int]:
        """Greedy assignment: each box's track index, -1 for none."""
        if not self._ids or not boxes:
            return [-1] * len(boxes)
        pred = self._predicted()
        if len(pred) * len(boxes) > self.SCALAR_MAX_PAIRS:
            pairs = self._scores_vectorised(pred, boxes)
        else:
            pairs = self._scores(pred, boxes)
        return greedy_assign(pairs, len(boxes))

    # --------------------------------------------------------------- update
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
        return np.array(self.update_rows(boxes.tolist(), hits.tolist()), np.int64)

    def update_rows(self, boxes_px: list, is_target: list[bool]) -> list[int]:
        """``update`` on plain Python rows: N (x, y, w, h) sequences and N bools; N track ids.

        The detector's per-frame entry point (no array round trip); the caller
        guarantees equal lengths.
        """
        if not self._bits and not boxes_px:  # no tracks, nothing seen: the usual quiet frame
            return []
        track_of = self._match(boxes_px)
        mask = self._window_mask
        bits = [(b << 1) & mask for b in self._bits]
        missed = [m + 1 for m in self._missed]
        ids, tracks_boxes, velocities, sightings = (
            self._ids,
            self._boxes,
            self._velocities,
            self._sightings,
        )
        a = self.velocity_smoothing
        ids_out = [0] * len(boxes_px)
        new = []
        for di, ti in enumerate(track_of):
            if ti < 0:
                new.append(di)
                continue
            x, y, w, h = box = boxes_px[di]
            ox, oy, ow, oh = tracks_boxes[ti]
            # velocity from the displacement since the track was last seen
            m = missed[ti]
            sx = ((x + w / 2) - (ox + ow / 2)) / m
            sy = ((y + h / 2) - (oy + oh / 2)) / m
            if sightings[ti] == 1:  # seen once: no velocity yet, take the first displacement whole
                velocities[ti] = [sx, sy]
            else:
                vx, vy = velocities[ti]
                velocities[ti] = [a * sx + (1 - a) * vx, a * sy + (1 - a) * vy]
            sightings[ti] += 1
            tracks_boxes[ti] = list(box)
            missed[ti] = 0
            bits[ti] |= bool(is_target[di])
            ids_out[di] = ids[ti]
        self._bits, self._missed = bits, missed
        limit = self.max_missed_frames
        if not new and all(m <= limit for m in missed):
            return ids_out
        # unmatched boxes start tracks; long-unseen tracks end
        keep = [t for t, m in enumerate(missed) if m <= limit]
        self._ids = [ids[t] for t in keep]
        self._boxes = [tracks_boxes[t] for t in keep]
        self._velocities = [velocities[t] for t in keep]
        self._missed = [missed[t] for t in keep]
        self._sightings = [sightings[t] for t in keep]
        self._bits = [bits[t] for t in keep]
        for di in new:
            ids_out[di] = self._next_id
            self._ids.append(self._next_id)
            self._next_id += 1
            self._boxes.append(list(boxes_px[di]))
            self._velocities.append([0.0, 0.0])
            self._missed.append(0)
            self._sightings.append(1)
            self._bits.append(int(bool(is_target[di])))
        return ids_out
