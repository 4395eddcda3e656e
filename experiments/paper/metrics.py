"""The paper's evaluation figures computed from scored rows (``experiments.paper.scenes``).

* ``confusions``: binary (target vs noise) and 5-class confusion matrices,
  counts and row-normalised (Fig. 9). The binary decision is the detector's
  (P(target) >= 0.5), the 5-class one is the most probable class.
* ``precision_recall``: PR curves and average precision (Fig. 10) from
  P(target) (binary) and per class one-vs-rest, with micro and macro averages
  (``sklearn.metrics.precision_recall_curve`` / ``average_precision_score``).
  Macro = the unweighted mean over classes that occur (a class with no
  instance has no defined AP).
* ``threshold_baseline``: the naive foreground-area baseline of section 7.
* ``window_detection``: eq. 12 against the rate measured over real windows.

Each takes the rows of one condition (night or day); ``Variant`` chooses
whether missed objects (targets the segmentation never delivered) count.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from sklearn.metrics import average_precision_score, confusion_matrix, precision_recall_curve

from detector.classes import CLASSES
from detector.confirm import p_detect_within
from experiments.paper.scenes import TARGET_THRESHOLD, SceneRecords

BINARY_CLASSES = ("noise", "target")
#: Row sets by name, each a mask over a ``SceneRecords``' rows: 'objects' counts missed objects
#: as answered 'noise' (what a lamp experiences); 'regions' scores only what the segmentation
#: delivered (the paper classified annotated regions); 'clean' also leaves out noise
#: detections lying on a target (fragments and merges an annotator would have given the
#: object's class or dropped).
VARIANT_ROWS: dict[str, Callable[[SceneRecords], np.ndarray]] = {
    "objects": lambda rec: np.ones(len(rec.truth_cls), dtype=bool),
    "regions": lambda rec: np.asarray(rec.detected, dtype=bool).reshape(-1),
    "clean": lambda rec: (
        np.asarray(rec.detected, dtype=bool) & ~np.asarray(rec.fragment, dtype=bool)
    ).reshape(-1),
}
VARIANTS = tuple(VARIANT_ROWS)


def row_normalised(counts: np.ndarray) -> np.ndarray:
    """Each row divided by its sum (rows with no instance stay 0: there is no rate to show)."""
    counts = np.asarray(counts, dtype=float)
    sums = counts.sum(axis=1, keepdims=True)
    return np.divide(counts, sums, out=np.zeros_like(counts), where=sums > 0)


@dataclass(frozen=True)
class Rows:
    """One condition's rows as arrays: truth class names, (N, 5) probabilities."""

    truth_cls: np.ndarray
    probabilities: np.ndarray

    @classmethod
    def of(cls, records: SceneRecords, variant: str) -> Rows:
        if variant not in VARIANT_ROWS:
            raise ValueError(f"variant: must be one of {VARIANTS}, got {variant!r}")
        keep = VARIANT_ROWS[variant](records)
        truth = np.asarray(records.truth_cls, dtype=object).reshape(-1)[keep]
        return cls(truth.astype(str), records.probability_matrix[keep])

    @property
    def truth_target(self) -> np.ndarray:
        return self.truth_cls != "noise"

    @property
    def p_target(self) -> np.ndarray:
        return 1.0 - self.probabilities[:, CLASSES.index("noise")]

    @property
    def predicted_cls(self) -> np.ndarray:
        return np.asarray(CLASSES)[self.probabilities.argmax(axis=1)]


@dataclass(frozen=True)
class Confusions:
    """Confusion counts (rows truth, columns predicted) and their row-normalised rates."""

    binary_counts: np.ndarray  # (2, 2) in BINARY_CLASSES order
    five_counts: np.ndarray  # (5, 5) in CLASSES order

    @property
    def binary(self) -> np.ndarray:
        return row_normalised(self.binary_counts)

    @property
    def five(self) -> np.ndarray:
        return row_normalised(self.five_counts)

    @property
    def tpr(self) -> float:
        """Targets called targets / targets (1 - FNR)."""
        return float(self.binary[1, 1])

    @property
    def fpr(self) -> float:
        """Noise regions called targets / noise regions."""
        return float(self.binary[0, 1])

    def rate(self, truth: str, predicted: str) -> float:
        """Row-normalised 5-class rate: share of ``truth`` instances predicted ``predicted``."""
        return float(self.five[CLASSES.index(truth), CLASSES.index(predicted)])


def confusions(rows: Rows) -> Confusions:
    if not len(rows.truth_cls):
        return Confusions(np.zeros((2, 2), dtype=np.int64), np.zeros((5, 5), dtype=np.int64))
    pred_target = rows.p_target >= TARGET_THRESHOLD
    binary = confusion_matrix(rows.truth_target, pred_target, labels=[False, True])
    five = confusion_matrix(rows.truth_cls, rows.predicted_cls, labels=list(CLASSES))
    return Confusions(binary, five)


@dataclass(frozen=True)
class Curve:
    """One precision-recall curve and its average precision (None if the class never occurs)."""

    precision: np.ndarray
    recall: np.ndarray
    ap: float | None
    positives: int
    samples: int

    @property
    def chance_ap(self) -> float | None:
        """AP of a random ranking: the share of positives."""
        return self.positives / self.samples if self.samples else None


def _curve(y_true: np.ndarray, score: np.ndarray) -> Curve:
    positives = int(np.count_nonzero(y_true))
    if positives == 0 or positives == len(y_true):
        # no negatives or no positives: precision or recall is undefined over thresholds
        ap = None if positives == 0 else 1.0
        return Curve(np.array([]), np.array([]), ap, positives, len(y_true))
    precision, recall, _ = precision_recall_curve(y_true, score)
    ap = float(average_precision_score(y_true, score))
    return Curve(precision, recall, ap, positives, len(y_true))


@dataclass(frozen=True)
class PrecisionRecall:
    binary: Curve
    per_class: dict[str, Curve]
    micro: Curve
    macro_ap: float | None

    def ap(self, cls: str) -> float | None:
        return self.per_class[cls].ap


def precision_recall(rows: Rows) -> PrecisionRecall:
    binary = _curve(rows.truth_target, rows.p_target)
    indicator = rows.truth_cls[:, None] == np.asarray(CLASSES)[None, :]
    per_class = {
        c: _curve(indicator[:, i], rows.probabilities[:, i]) for i, c in enumerate(CLASSES)
    }
    micro = _curve(indicator.ravel(), rows.probabilities.ravel())
    aps = [c.ap for c in per_class.values() if c.ap is not None]
    return PrecisionRecall(binary, per_class, micro, float(np.mean(aps)) if aps else None)


@dataclass(frozen=True)
class BaselineRates:
    """The foreground-area baseline at one threshold (fraction of the frame area).

    Per instance (the paper's unit: its Table 2 counts annotated regions per
    frame): ``tpr`` = eligible target instances whose region's contour area
    exceeds the threshold; ``fpr`` = regions matching no object that exceed
    it. Per frame: ``frame_tpr`` = frames with an eligible target in which any
    region exceeds it; ``frame_fpr`` = frames with no target at all in which
    any region exceeds it (the lamp would switch on for nothing).
    """

    threshold_fraction: float
    tpr: float | None
    fpr: float | None
    frame_tpr: float | None
    frame_fpr: float | None
    target_instances: int
    noise_regions: int
    target_frames: int
    empty_frames: int


def _share(mask: np.ndarray) -> float | None:
    return float(np.mean(mask)) if mask.size else None


def threshold_baseline(records: SceneRecords, threshold_fraction: float) -> BaselineRates:
    if not 0.0 < threshold_fraction < 1.0:
        raise ValueError(f"threshold_fraction: must be in (0, 1), got {threshold_fraction!r}")
    target = np.asarray(records.target_area_frac, dtype=float)
    noise = np.asarray(records.noise_area_frac, dtype=float)
    frame_max = np.asarray(records.frame_max_frac, dtype=float)
    has_target = np.asarray(records.frame_has_target, dtype=bool)
    empty = np.asarray(records.frame_target_free, dtype=bool)
    fires = frame_max > threshold_fraction
    return BaselineRates(
        threshold_fraction,
        _share(target > threshold_fraction),
        _share(noise > threshold_fraction),
        _share(fires[has_target]),
        _share(fires[empty]),
        int(target.size),
        int(noise.size),
        int(has_target.sum()),
        int(empty.sum()),
    )


@dataclass(frozen=True)
class WindowCheck:
    """Eq. 12 beside what happened: objects detected in more than half of n consecutive frames."""

    n: int
    p_frame: float | None  # per-frame detection rate of eligible targets
    predicted: float | None  # eq. 12 with p_frame
    #: share of n-frame windows (n consecutive eligible frames of one object) with > n/2 hits
    measured: float | None
    windows: int


def window_detection(records: SceneRecords, n: int = 5) -> WindowCheck:
    hits_all: list[bool] = []
    majority: list[bool] = []
    for seq in records.hits.values():
        frames = np.array([f for f, _ in seq])
        hits = np.array([h for _, h in seq], dtype=int)
        hits_all.extend(hits.astype(bool).tolist())
        if len(seq) < n:
            continue
        # windows of n consecutive frame indices in which the object was eligible throughout
        counts = np.convolve(hits, np.ones(n, dtype=int), mode="valid")
        contiguous = frames[n - 1 :] - frames[: len(frames) - n + 1] == n - 1
        majority.extend((counts[contiguous] > n // 2).tolist())
    p = float(np.mean(hits_all)) if hits_all else None
    return WindowCheck(
        n,
        p,
        None if p is None else p_detect_within(p, n),
        float(np.mean(majority)) if majority else None,
        len(majority),
    )


#: Distance bands (m) for the miss-rate-by-range table: the paper blames its night misses on range.
DISTANCE_BANDS_M = ((0.0, 10.0), (10.0, 20.0), (20.0, 30.0), (30.0, 40.0), (40.0, 50.0))


@dataclass(frozen=True)
class BandRate:
    lo_m: float
    hi_m: float
    targets: int  # target rows (objects variant) whose object was at lo_m <= d < hi_m
    tpr: float | None
    missed: float | None  # share never delivered by the segmentation (or too far / cut)


def tpr_by_distance(records: SceneRecords) -> list[BandRate]:
    """Binary TPR of target rows ('objects' variant) per forward-distance band."""
    rows = Rows.of(records, "objects")
    dist = np.asarray(records.distance_m, dtype=float).reshape(-1)
    detected = np.asarray(records.detected, dtype=bool).reshape(-1)
    hit = rows.p_target >= TARGET_THRESHOLD
    out = []
    for lo, hi in DISTANCE_BANDS_M:
        m = rows.truth_target & (dist >= lo) & (dist < hi)
        n = int(m.sum())
        out.append(BandRate(lo, hi, n, _share(hit[m]), _share(~detected[m])))
    return out
