"""The paper's detector end to end: one grayscale frame in, classified moving objects out.

    segment (CLAHE, MOG2, morphology, contours)
    -> features of every inner region (eqs. 1-11, one vectorised call)
    -> division of regions merged with their light spot (section 5.2)
    -> one classifier call for all kept regions (section 5.4)
    -> track ids across frames (section 8.2)

Regions touching the frame border are not classified (their shape is cut);
neither are regions with no ground point (bottom at or above the horizon) or
farther than ``max_distance_m`` (the paper's range is 25 m). Boxes are OpenCV
``(x, y, w, h)`` pixels of the distorted frame; distances are forward ground
distances, m (see ``detector.camera``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import sklearn
from sklearn.linear_model import LogisticRegression
from sklearn.preprocessing import PolynomialFeatures, StandardScaler

from detector.camera import CameraModel
from detector.classifier import DimensionalClassifier, default_model
from detector.confirm import Tracker
from detector.divide import DivisionParams, divide_regions
from detector.features import region_features
from detector.segment import Regions, Segmenter, SegmenterParams

# frozen, so one shared default instance is safe
_DEFAULT_SEGMENTER_PARAMS = SegmenterParams()
_DEFAULT_DIVISION_PARAMS = DivisionParams()


@dataclass(frozen=True)
class Detection:
    """One classified region of one frame.

    ``features`` are ``detector.features.FEATURE_NAMES`` (width m, height m,
    area m^2, distance m, tilt deg, camera height m); ``probabilities`` follow
    the model's ``classes_`` (``detector.classifier.CLASSES``); ``p_target`` is
    1 - P(noise).
    """

    box_px: tuple[int, int, int, int]
    features: np.ndarray
    cls: str
    probabilities: np.ndarray
    p_target: float
    track_id: int | None


class Detector:
    """Per-camera detector: owns the background model and the tracker."""

    def __init__(
        self,
        camera: CameraModel,
        model: DimensionalClassifier | None = None,
        params: SegmenterParams = _DEFAULT_SEGMENTER_PARAMS,
        max_distance_m: float = 25.0,
        target_threshold: float = 0.5,
        *,
        division: DivisionParams = _DEFAULT_DIVISION_PARAMS,
        tracker: Tracker | None = None,
    ) -> None:
        if not isinstance(camera, CameraModel):
            raise TypeError(f"Detector camera must be a CameraModel, got {type(camera).__name__}")
        if not max_distance_m > 0:
            raise ValueError(f"Detector max_distance_m must be > 0 m, got {max_distance_m!r}")
        if not 0.0 <= target_threshold <= 1.0:
            raise ValueError(
                f"Detector target_threshold must be in [0, 1], got {target_threshold!r}"
            )
        self.camera = camera
        self.model = default_model() if model is None else model
        classes = np.asarray(getattr(self.model, "classes_", ()))
        if "noise" not in classes:
            raise ValueError(
                f"Detector model must be fitted with a 'noise' class, got classes {classes.tolist()}"
            )
        self._classes = classes
        self._noise_col = int(np.flatnonzero(classes == "noise")[0])
        self._predict_proba = numpy_predict_proba(self.model, camera) or self._sklearn_predict_proba
        self.max_distance_m = float(max_distance_m)
        self.target_threshold = float(target_threshold)
        self.division = division
        self.segmenter = Segmenter(params)
        self.tracker = Tracker() if tracker is None else tracker
        self.last_regions: Regions = Regions.empty(camera.height_px, camera.width_px)
        self._no_boxes = np.zeros((0, 4))

    def reset_background(self) -> None:
        """Rebuild the background model (call when the lamp in view switches)."""
        self.segmenter.reset()

    def is_target(self, detections: Sequence[Detection]) -> bool:
        """Whether any detection is a target at this detector's threshold."""
        return any(d.p_target >= self.target_threshold for d in detections)

    def _sklearn_predict_proba(self, feats: np.ndarray) -> np.ndarray:
        # the rows are finite by construction (valid), so skip scikit-learn's re-check
        with sklearn.config_context(assume_finite=True):
            return self.model.predict_proba(feats)

    def process(self, gray: np.ndarray) -> list[Detection]:
        """Detect and classify the moving objects of one uint8 (H, W) frame."""
        expected = (self.camera.height_px, self.camera.width_px)
        if not isinstance(gray, np.ndarray) or gray.shape != expected or gray.dtype != np.uint8:
            got = (
                f"{gray.dtype} {gray.shape}"
                if isinstance(gray, np.ndarray)
                else type(gray).__name__
            )
            raise ValueError(
                f"Detector.process needs a grayscale uint8 frame of shape {expected} (the camera's "
                f"height_px x width_px), got {got}"
            )
        regions = self.segmenter.apply(gray)
        self.last_regions = regions
        inner = np.flatnonzero(~regions.touches_border)
        if len(inner) == 0:
            self.tracker.update(self._no_boxes)
            return []
        boxes, areas = regions.boxes_px[inner], regions.areas_px[inner]
        feats, valid = region_features(self.camera, boxes, areas)
        parts = divide_regions(
            self.camera,
            [regions.contours[i] for i in inner],
            boxes,
            areas,
            feats,
            valid,
            self.division,
        )
        # NaN distances (no ground point) compare False
        keep = np.flatnonzero(parts.valid & (parts.features[:, 3] <= self.max_distance_m))
        if len(keep) == 0:
            self.tracker.update(self._no_boxes)
            return []
        feats = parts.features[keep]
        boxes = parts.boxes_px[keep]
        proba = self._predict_proba(feats)
        p_target = 1.0 - proba[:, self._noise_col]
        labels = self._classes[np.argmax(proba, axis=1)]
        ids = self.tracker.update(boxes, p_target >= self.target_threshold)
        return [
            Detection(
                box_px=(int(b[0]), int(b[1]), int(b[2]), int(b[3])),
                features=feats[j],
                cls=str(labels[j]),
                probabilities=proba[j],
                p_target=float(p_target[j]),
                track_id=int(ids[j]),
            )
            for j, b in enumerate(boxes.tolist())
        ]


def numpy_predict_proba(
    model: DimensionalClassifier, camera: CameraModel
) -> Callable[[np.ndarray], np.ndarray] | None:
    """``model.predict_proba`` as plain numpy, or None when the model is not the known pipeline.

    Why: scikit-learn validates its input at every pipeline step, about 0.4 ms
    per call, a fifth of OpenCV's whole work on a 320 x 240 frame; the
    arithmetic of StandardScaler -> PolynomialFeatures -> LogisticRegression is
    a few tens of microseconds. The numpy version is used only if it agrees
    with ``model.predict_proba`` (to 1e-9) on probe rows spanning the
    feature ranges at this camera's tilt and height; otherwise the detector
    calls ``predict_proba`` itself.
    """
    pipe = getattr(model, "pipeline_", None)
    steps = [step for _, step in getattr(pipe, "steps", ())]
    if len(steps) != 3:
        return None
    scaler, poly, logreg = steps
    if not (
        type(scaler) is StandardScaler
        and type(poly) is PolynomialFeatures
        and type(logreg) is LogisticRegression
    ):
        return None
    mean = scaler.mean_ if scaler.with_mean else 0.0
    scale = scaler.scale_ if scaler.with_std else 1.0
    powers = np.asarray(poly.powers_)  # (n_out, n_in) exponents
    if powers.sum(axis=1).max() > 2:
        return None
    # each output term is z_i * z_j, with index n_in standing for the constant 1
    n_in = powers.shape[1]
    first = np.empty(len(powers), np.intp)
    second = np.empty(len(powers), np.intp)
    for row, exps in enumerate(powers):
        factors = np.repeat(np.arange(n_in), exps).tolist() + [n_in, n_in]
        first[row], second[row] = factors[0], factors[1]
    weights, bias = logreg.coef_.T, logreg.intercept_
    columns = np.asarray(pipe.classes_)
    n_classes = len(model.classes_)

    def proba(features: np.ndarray) -> np.ndarray:
        z = np.ones((len(features), n_in + 1))
        z[:, :n_in] = (features - mean) / scale
        logits = (z[:, first] * z[:, second]) @ weights + bias
        if logits.shape[1] == 1:  # two classes: one logistic output
            p1 = 1.0 / (1.0 + np.exp(-logits[:, 0]))
            p = np.column_stack([1.0 - p1, p1])
        else:
            e = np.exp(logits - logits.max(axis=1, keepdims=True))
            p = e / e.sum(axis=1, keepdims=True)
        out = np.zeros((len(features), n_classes))
        out[:, columns] = p
        return out

    rng = np.random.default_rng(0)
    probe = np.column_stack(
        [
            rng.uniform(0.05, 6.0, 256),
            rng.uniform(0.05, 3.0, 256),
            rng.uniform(0.01, 12.0, 256),
            rng.uniform(1.0, 40.0, 256),
            np.full(256, camera.tilt_deg),
            np.full(256, camera.height_m),
        ]
    )
    try:
        agrees = np.allclose(proba(probe), model.predict_proba(probe), rtol=0.0, atol=1e-9)
    except (ValueError, IndexError, AttributeError):
        return None
    return proba if agrees else None
