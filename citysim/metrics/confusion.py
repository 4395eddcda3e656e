"""Per-frame detection quality against render ground truth, streamed.

Truth objects (``citysim.render.camera.TruthObject``) and detections
(``detector.detector.Detection``) are read by attribute only, so this module
imports neither. Boxes are OpenCV rects ``(x, y, w, h)`` in pixels.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from citysim.config.kinds import AGENT_KINDS, DETECTOR_CLASSES
from citysim.control.lamps import check_number
from citysim.metrics.collector import Collector

#: Detector class order (detector.classes.CLASSES): rows/columns of ``confusion_5``.
CONFUSION_CLASSES = DETECTOR_CLASSES
_CLASS_INDEX = {cls: i for i, cls in enumerate(CONFUSION_CLASSES)}
#: The detector's target classes: passes are counted per class it should call them.
_TARGET_DETECTOR_CLASSES = DETECTOR_CLASSES[1:]


@functools.cache  # asked per truth object per frame; the kinds' records are fixed
def scored_as(cls: str) -> str:
    """The detector class a truth object of kind ``cls`` is scored as (its record's
    ``detector_class``; an unknown kind is noise)."""
    kind = AGENT_KINDS.get(cls)
    return kind.detector_class if kind is not None else "noise"


class TruthLike(Protocol):
    """What is read of a ``citysim.render.camera.TruthObject``."""

    object_id: int
    cls: str
    x: int
    y: int
    w: int
    h: int
    fully_visible: bool


class DetectionLike(Protocol):
    """What is read of a ``detector.detector.Detection``."""

    box_px: tuple[int, int, int, int]
    cls: str
    p_target: float


def iou_matrix(boxes_a: np.ndarray, boxes_b: np.ndarray) -> np.ndarray:
    """IoU of every (x, y, w, h) box in ``boxes_a`` with every box in ``boxes_b`` (OpenCV rects, px)."""
    a = np.asarray(boxes_a, dtype=float).reshape(-1, 4)[:, None, :]
    b = np.asarray(boxes_b, dtype=float).reshape(-1, 4)[None, :, :]
    iw = np.clip(
        np.minimum(a[..., 0] + a[..., 2], b[..., 0] + b[..., 2]) - np.maximum(a[..., 0], b[..., 0]),
        0,
        None,
    )
    ih = np.clip(
        np.minimum(a[..., 1] + a[..., 3], b[..., 1] + b[..., 3]) - np.maximum(a[..., 1], b[..., 1]),
        0,
        None,
    )
    inter = iw * ih
    union = a[..., 2] * a[..., 3] + b[..., 2] * b[..., 3] - inter
    return np.where(union > 0, inter / np.where(union > 0, union, 1.0), 0.0)


def greedy_match(iou: np.ndarray, threshold: float) -> list[tuple[int, int]]:
    """Pairs (row, col) taken in order of decreasing IoU, each row and column once, IoU >= threshold."""
    pairs: list[tuple[int, int]] = []
    used_r, used_c = set(), set()
    flat = np.argsort(-iou, axis=None, kind="stable")
    for r, c in zip(*np.unravel_index(flat, iou.shape), strict=True):
        if iou[r, c] < threshold:
            break
        if r not in used_r and c not in used_c:
            pairs.append((int(r), int(c)))
            used_r.add(r)
            used_c.add(c)
    return pairs


def match_boxes(boxes_a: Sequence, boxes_b: Sequence, threshold: float) -> list[tuple[int, int]]:
    """``greedy_match(iou_matrix(boxes_a, boxes_b), threshold)`` on plain floats, for a frame's few
    boxes (numpy's per-call cost was most of the scoring). The same IEEE operations in the same
    order give the same IoUs; Python's sort is stable, as the matrix's argsort, so ties are taken
    in the same (row-major) order and the pairs are the same."""
    ious: list[float] = []
    for ax, ay, aw, ah in boxes_a:
        ax, ay, aw, ah = float(ax), float(ay), float(aw), float(ah)
        for bx, by, bw, bh in boxes_b:
            bx, by, bw, bh = float(bx), float(by), float(bw), float(bh)
            iw = max(min(ax + aw, bx + bw) - max(ax, bx), 0.0)
            ih = max(min(ay + ah, by + bh) - max(ay, by), 0.0)
            inter = iw * ih
            union = aw * ah + bw * bh - inter
            ious.append(inter / union if union > 0 else 0.0)
    n_b = len(boxes_b)
    pairs: list[tuple[int, int]] = []
    used_r, used_c = set(), set()
    for flat in sorted(range(len(ious)), key=lambda k: -ious[k]):
        if ious[flat] < threshold:
            break
        r, c = divmod(flat, n_b)
        if r not in used_r and c not in used_c:
            pairs.append((r, c))
            used_r.add(r)
            used_c.add(c)
    return pairs


@dataclass
class _Pass:
    cls: str
    last_seen_s: float
    fully_seen: bool = False
    detected: bool = False


class DetectionConfusion:
    """Per-frame detection quality against render ground truth, streamed.

    Truth objects are scored as their kind's ``detector_class`` (an animal as 'noise', an
    e-scooter as a 'cyclist'), passes too (``miss_rate_by_class``); a
    detection that matches no truth box is a noise region. A detection is a
    target if ``p_target >= target_threshold`` (the ``Detector`` rule); the
    5-class confusion uses its ``cls``. A *pass* is one object in view of one
    lamp's camera; it ends when that camera has not seen it for ``pass_gap_s``.
    A pass is missed when the object was fully visible in at least one frame
    and never matched by a target detection.
    """

    def __init__(
        self, iou_threshold: float = 0.3, target_threshold: float = 0.5, pass_gap_s: float = 2.0
    ) -> None:
        check_number("DetectionConfusion", "iou_threshold", iou_threshold, 0.0, 1.0)
        check_number("DetectionConfusion", "target_threshold", target_threshold, 0.0, 1.0)
        check_number("DetectionConfusion", "pass_gap_s", pass_gap_s, 0.0)
        self.iou_threshold = iou_threshold
        self.target_threshold = target_threshold
        self.pass_gap_s = pass_gap_s
        # counted in plain ints (a numpy element's += cost ~10x): ``confusion_5`` is its array
        self._confusion = [[0] * len(CONFUSION_CLASSES) for _ in CONFUSION_CLASSES]
        self.tp = self.fp = self.fn = self.tn = 0
        self.frames = self.regions = self.noise_regions = 0
        self._passes: dict[int, dict[int, _Pass]] = {}
        #: per lamp, at most the earliest last sighting of its passes (a sighting only moves it later):
        #: the frames before any pass can end skip the scan of them (``_end_passes``)
        self._earliest_seen_s: dict[int, float] = {}
        # detector class -> [eligible, missed]
        self._pass_counts = {c: [0, 0] for c in _TARGET_DETECTOR_CLASSES}

    @property
    def confusion_5(self) -> np.ndarray:
        """Counts of (truth class, detected class), rows and columns ``CONFUSION_CLASSES``."""
        return np.array(self._confusion, dtype=np.int64)

    @staticmethod
    def _index(cls: str, field_name: str) -> int:
        if cls in CONFUSION_CLASSES:
            return CONFUSION_CLASSES.index(cls)
        raise ValueError(
            f"DetectionConfusion.add {field_name}: class must be one of {CONFUSION_CLASSES}, got {cls!r}"
        )

    def add(
        self,
        truth: Sequence[TruthLike],
        detections: Sequence[DetectionLike],
        lamp_index: int,
        t_s: float,
    ) -> None:
        """Count one frame of lamp ``lamp_index``'s camera at ``t_s`` (s)."""
        if not truth and not detections:  # most judged frames: nothing to count but the frame
            self.frames += 1
            if self._passes.get(lamp_index):
                self._end_passes(lamp_index, t_s)
            return
        self._add_matched(truth, detections, lamp_index, t_s)

    def _add_matched(self, truth: Sequence[TruthLike], detections: Sequence[DetectionLike], lamp_index: int,
                     t_s: float) -> None:  # fmt: skip
        """``add`` of a frame with road users or detections: matched to the truth boxes, each counted."""
        truth_cls = [scored_as(t.cls) for t in truth]
        det_cls = [_CLASS_INDEX.get(d.cls) for d in detections]
        if None in det_cls:  # the error ``_index`` gives
            det_cls = [self._index(d.cls, "detections.cls") for d in detections]
        self.frames += 1
        matched_truth: dict[int, int] = {}
        det_target: list[bool] = []
        if detections:
            det_target = [d.p_target >= self.target_threshold for d in detections]
            pairs: list[tuple[int, int]] = []
            if truth:  # without both, nothing to match, no IoU to compute
                pairs = match_boxes([(t.x, t.y, t.w, t.h) for t in truth], [d.box_px for d in detections],
                                    self.iou_threshold)
            self.regions += len(detections)
            matched_truth = dict(pairs)
            matched_dets = {c for _, c in pairs}
            for r, c in pairs:
                self._count(truth_cls[r], det_cls[c], det_target[c])
            for c in range(len(detections)):
                if c not in matched_dets:
                    self._count("noise", det_cls[c], det_target[c])
        passes = self._passes.setdefault(lamp_index, {})
        gap_s = self.pass_gap_s
        for r, t in enumerate(truth):
            cls = truth_cls[r]
            if cls == "noise":
                continue
            c = matched_truth.get(r)
            fully_visible = t.fully_visible
            if c is None and fully_visible:
                self._count(cls, 0, False)
            object_id = t.object_id
            p = passes.get(object_id)
            if p is not None and t_s - p.last_seen_s > gap_s:
                self._end_pass(p)  # back in view after a gap: that was one pass, this is another
                p = None
            if p is None:
                p = passes[object_id] = _Pass(cls, t_s)
                self._seen_since(lamp_index, t_s)
            p.last_seen_s = t_s
            p.fully_seen |= bool(fully_visible)
            p.detected |= c is not None and det_target[c]
        if passes and t_s - self._earliest_seen_s[lamp_index] > gap_s:  # else ``_end_passes`` ends none
            self._end_passes(lamp_index, t_s)

    def _end_passes(self, lamp_index: int, t_s: float) -> None:
        """End lamp ``lamp_index``'s passes unseen for more than ``pass_gap_s`` at ``t_s``."""
        passes = self._passes.get(lamp_index)
        if not passes or t_s - self._earliest_seen_s[lamp_index] <= self.pass_gap_s:
            return  # none unseen long enough: t_s - last_seen_s is at most t_s - the earliest (IEEE)
        for object_id in [i for i, p in passes.items() if t_s - p.last_seen_s > self.pass_gap_s]:
            self._end_pass(passes.pop(object_id))
        if passes:
            self._earliest_seen_s[lamp_index] = min(p.last_seen_s for p in passes.values())
        else:
            del self._earliest_seen_s[lamp_index]

    def _seen_since(self, lamp_index: int, t_s: float) -> None:
        """A pass of lamp ``lamp_index`` began at ``t_s``: keep the earliest last sighting a lower bound."""
        self._earliest_seen_s[lamp_index] = min(self._earliest_seen_s.get(lamp_index, t_s), t_s)

    def _count(self, truth_cls: str, pred_index: int, pred_target: bool) -> None:
        self._confusion[_CLASS_INDEX[truth_cls]][pred_index] += 1
        if truth_cls == "noise":
            self.noise_regions += 1
            self.fp += int(pred_target)
            self.tn += int(not pred_target)
        else:
            self.tp += int(pred_target)
            self.fn += int(not pred_target)

    def _end_pass(self, p: _Pass) -> None:
        if p.fully_seen:
            self._pass_counts[p.cls][0] += 1
            self._pass_counts[p.cls][1] += int(not p.detected)

    def finish(self) -> None:
        """End every open pass (call once after the last frame)."""
        for passes in self._passes.values():
            for p in passes.values():
                self._end_pass(p)
            passes.clear()

    def summary(self) -> dict[str, Any]:
        """Counts and tn-free rates; ``miss_rate`` per pass (overall and ``miss_rate_by_class``)."""

        def ratio(num: int, den: int) -> float | None:
            return num / den if den else None

        eligible = sum(v[0] for v in self._pass_counts.values())
        missed = sum(v[1] for v in self._pass_counts.values())
        return {
            "frames": self.frames,
            "regions": self.regions,
            "tp": self.tp,
            "fp": self.fp,
            "fn": self.fn,
            "tn": self.tn,
            "tpr": ratio(self.tp, self.tp + self.fn),
            "precision": ratio(self.tp, self.tp + self.fp),
            "fpr": ratio(self.fp, self.noise_regions),
            "fp_per_frame": ratio(self.fp, self.frames),
            "fp_per_region": ratio(self.fp, self.regions),
            "confusion_5": self.confusion_5.tolist(),
            "confusion_classes": list(CONFUSION_CLASSES),
            "object_passes": eligible,
            "missed_passes": missed,
            "miss_rate": ratio(missed, eligible),
            "miss_rate_by_class": {c: ratio(v[1], v[0]) for c, v in self._pass_counts.items()},
        }


class ConfusionCollector(Collector):
    """Feeds every judged frame to a ``DetectionConfusion``; its summary goes under ``detection``."""

    def __init__(self) -> None:
        self.confusion = DetectionConfusion()

    def on_frame(self, lamp_index: int, t_s: float, truth: Sequence, detections: Sequence | None) -> None:
        if detections is not None:
            self.confusion.add(truth, detections, lamp_index, t_s)

    def finish(self, t_end_s: float) -> dict[str, Any]:
        self.confusion.finish()
        return {"detection": self.confusion.summary() if self.confusion.frames else {}}
