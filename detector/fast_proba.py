"""The classifier's probabilities without scikit-learn's per-call cost, for the detector's frames.

A fitted ``DimensionalClassifier`` is StandardScaler -> PolynomialFeatures(2) ->
LogisticRegression; its arithmetic is a quadratic polynomial per class. Why:
scikit-learn validates its input at every pipeline step, which costs more than
OpenCV's work on a small frame. ``numpy_predict_proba`` evaluates the
polynomial with numpy (frames with many regions), ``camera_rows_proba`` in
plain Python with the camera's fixed tilt and height folded in (a frame's
handful of regions). Each is used only if it agrees with ``predict_proba`` to
1e-9 on probe rows at the camera's tilt and height; otherwise None, and the
detector calls ``predict_proba`` itself. ``compiled_rows_proba`` is
``camera_rows_proba``'s arithmetic compiled (numba), operation for operation, used
only if it gives the plain Python rows' values bit for bit.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numba import njit
from sklearn.linear_model import LogisticRegression
from sklearn.preprocessing import PolynomialFeatures, StandardScaler

from detector.camera import CameraModel
from detector.classifier import DimensionalClassifier
from detector.features import FEATURE_NAMES, N_FEATURES

# one camera's regions all share these two features; the rest vary per region
_TILT_COLUMN = FEATURE_NAMES.index("tilt_deg")
_HEIGHT_COLUMN = FEATURE_NAMES.index("camera_height_m")
_FREE_COLUMNS = tuple(i for i in range(N_FEATURES) if i not in (_TILT_COLUMN, _HEIGHT_COLUMN))


@dataclass(frozen=True)
class _QuadraticModel:
    """The arithmetic of a fitted StandardScaler -> PolynomialFeatures(2) -> LogisticRegression.

    Logits are ``bias + sum_t weights[t] * z[first[t]] * z[second[t]]`` with
    ``z = (x - mean) / scale`` extended by a constant 1 at index ``n_in``;
    ``columns`` are the model's ``classes_`` columns of the pipeline's outputs.
    """

    mean: np.ndarray | float
    scale: np.ndarray | float
    first: np.ndarray  # (n_terms,) int
    second: np.ndarray  # (n_terms,) int
    weights: np.ndarray  # (n_terms, n_logits)
    bias: np.ndarray  # (n_logits,)
    columns: np.ndarray  # (n_outputs,) int
    n_in: int
    n_classes: int


def _quadratic_model(model: object) -> _QuadraticModel | None:
    """The pipeline's arithmetic, or None when the model is not the known pipeline."""
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
    return _QuadraticModel(
        mean=scaler.mean_ if scaler.with_mean else 0.0,
        scale=scaler.scale_ if scaler.with_std else 1.0,
        first=first,
        second=second,
        weights=logreg.coef_.T,
        bias=logreg.intercept_,
        columns=np.asarray(pipe.classes_),
        n_in=n_in,
        n_classes=len(model.classes_),
    )


def _probe_rows(camera: CameraModel) -> np.ndarray:
    """(256, 6) feature rows spanning the classes' ranges at this camera's tilt and height."""
    rng = np.random.default_rng(0)
    return np.column_stack(
        [
            rng.uniform(0.05, 6.0, 256),
            rng.uniform(0.05, 3.0, 256),
            rng.uniform(0.01, 12.0, 256),
            rng.uniform(1.0, 40.0, 256),
            np.full(256, camera.tilt_deg),
            np.full(256, camera.height_m),
        ]
    )


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
    q = _quadratic_model(model)
    if q is None:
        return None
    mean, scale, first, second, n_in = q.mean, q.scale, q.first, q.second, q.n_in
    weights, bias, columns, n_classes = q.weights, q.bias, q.columns, q.n_classes

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

    return proba if _agrees(proba, model, camera) else None


def _agrees(proba: Callable[[np.ndarray], np.ndarray], model: object, camera: CameraModel) -> bool:
    """Whether ``proba`` equals ``model.predict_proba`` to 1e-9 on this camera's probe rows."""
    probe = _probe_rows(camera)
    try:
        return bool(np.allclose(proba(probe), model.predict_proba(probe), rtol=0.0, atol=1e-9))
    except (ValueError, IndexError, AttributeError, OverflowError):
        return False


def camera_rows_proba(
    model: DimensionalClassifier, camera: CameraModel
) -> Callable[[list[list[float]]], list[list[float]]] | None:
    """``model.predict_proba`` for one camera's feature rows, in plain Python; None if unavailable.

    Input rows are lists of the six ``FEATURE_NAMES`` values whose tilt and
    camera height are this camera's (they are not read: a detector's rows all
    carry its camera's); output rows are probabilities in ``classes_`` order.
    Why: a frame has a handful of regions, and numpy's per-call dispatch costs
    several times the arithmetic. The camera's fixed tilt and height and the
    standardisation are folded into one quadratic polynomial of width, height,
    area and distance per class, so a row costs 14 products and a sum per class.
    Used only if it agrees with ``model.predict_proba`` (to 1e-9) on probe rows
    at this camera's tilt and height.
    """
    q = _quadratic_model(model)
    if q is None or q.n_in != N_FEATURES:
        return None
    # z~ = T u~ with u~ = (width, height, area, distance, 1) and z~ = (z_0 .. z_5, 1)
    n_free = len(_FREE_COLUMNS)
    mean = np.broadcast_to(np.asarray(q.mean, np.float64), (N_FEATURES,))
    scale = np.broadcast_to(np.asarray(q.scale, np.float64), (N_FEATURES,))
    fixed = {_TILT_COLUMN: camera.tilt_deg, _HEIGHT_COLUMN: camera.height_m}
    t = np.zeros((N_FEATURES + 1, n_free + 1))
    for j, i in enumerate(_FREE_COLUMNS):
        t[i, j] = 1.0 / scale[i]
        t[i, n_free] = -mean[i] / scale[i]
    for i, value in fixed.items():
        t[i, n_free] = (value - mean[i]) / scale[i]
    t[N_FEATURES, n_free] = 1.0
    n_logits = q.weights.shape[1]
    a = np.zeros((n_logits, N_FEATURES + 1, N_FEATURES + 1))
    for term, (i, j) in enumerate(zip(q.first, q.second, strict=True)):
        a[:, i, j] += q.weights[term]
    b = t.T @ a @ t
    sym = (b + b.transpose(0, 2, 1)) / 2
    # coefficients of u_i u_j (i <= j, with u_4 = 1) in the order the rows build them
    pairs = [(i, j) for i in range(n_free + 1) for j in range(i, n_free + 1)][:-1]
    coefs = [
        [float(sym[c, i, j] * (1.0 if i == j else 2.0)) for i, j in pairs] for c in range(n_logits)
    ]
    consts = [float(sym[c, n_free, n_free] + q.bias[c]) for c in range(n_logits)]
    per_class = list(zip(consts, coefs, strict=True))
    columns = q.columns.tolist()
    # what compiled_rows_proba evaluates, operation for operation
    proba_rows_constants = (np.array(consts), np.array(coefs), q.columns.astype(np.int64), q.n_classes)
    n_classes = q.n_classes
    direct = columns == list(range(n_classes))

    def proba_rows(rows: list[list[float]]) -> list[list[float]]:
        out = []
        for row in rows:
            w, h, ar, d = row[0], row[1], row[2], row[3]
            terms = (w * w, w * h, w * ar, w * d, w, h * h, h * ar, h * d, h, ar * ar, ar * d, ar)
            terms += (d * d, d)
            logits = [c0 + sum(map(operator.mul, cf, terms)) for c0, cf in per_class]
            if n_logits == 1:  # two classes: one logistic output
                z = logits[0]
                p1 = 1.0 / (1.0 + math.exp(-z)) if z >= 0 else math.exp(z) / (1.0 + math.exp(z))
                p = [1.0 - p1, p1]
            else:
                top = max(logits)
                e = [math.exp(v - top) for v in logits]
                total = sum(e)
                p = [v / total for v in e]
            if not direct:
                full = [0.0] * n_classes
                for col, v in zip(columns, p, strict=True):
                    full[col] = v
                p = full
            out.append(p)
        return out

    def proba(features: np.ndarray) -> np.ndarray:
        return np.array(proba_rows(features.tolist())).reshape(len(features), n_classes)

    proba_rows.constants = proba_rows_constants
    return proba_rows if _agrees(proba, model, camera) else None


@njit(cache=True, nogil=True)
def _polynomial_rows(feats, consts, coefs, columns, out):  # pragma: no cover - compiled
    """``camera_rows_proba``'s ``proba_rows`` on the rows of ``feats`` (N, 6) into ``out`` (N,
    classes, zeros): the same float64 operations in the same order (sums from 0 left to right,
    as Python's ``sum``; no fast-math, so no reassociation or fused multiply-add)."""
    n_logits = consts.shape[0]
    terms = np.empty(14)
    logits = np.empty(n_logits)
    e = np.empty(n_logits)
    for r in range(feats.shape[0]):
        w, h, ar, d = feats[r, 0], feats[r, 1], feats[r, 2], feats[r, 3]
        terms[0], terms[1], terms[2], terms[3], terms[4] = w * w, w * h, w * ar, w * d, w
        terms[5], terms[6], terms[7], terms[8] = h * h, h * ar, h * d, h
        terms[9], terms[10], terms[11], terms[12], terms[13] = ar * ar, ar * d, ar, d * d, d
        for c in range(n_logits):
            total = 0.0
            for t in range(14):
                total += coefs[c, t] * terms[t]
            logits[c] = consts[c] + total
        if n_logits == 1:  # two classes: one logistic output
            z = logits[0]
            p1 = 1.0 / (1.0 + math.exp(-z)) if z >= 0 else math.exp(z) / (1.0 + math.exp(z))
            out[r, columns[0]] = 1.0 - p1
            out[r, columns[1]] = p1
            continue
        top = logits[0]
        for c in range(1, n_logits):
            if logits[c] > top:  # as Python's max: the first of equal values
                top = logits[c]
        total = 0.0
        for c in range(n_logits):
            e[c] = math.exp(logits[c] - top)
            total += e[c]
        for c in range(n_logits):
            out[r, columns[c]] = e[c] / total


def compiled_rows_proba(
    rows_proba: Callable[[list[list[float]]], list[list[float]]] | None, camera: CameraModel
) -> Callable[[np.ndarray], np.ndarray] | None:
    """``rows_proba`` (``camera_rows_proba``'s, for ``camera``) compiled: feature rows (N, 6)
    float64 in, probabilities (N, classes) out, equal bit for bit to the plain Python rows'
    (checked on probe rows here; None if they differ anywhere, or ``rows_proba`` is None).

    Why: the plain Python rows cost several microseconds per region, more after MOG2 has
    walked the caches; one compiled call costs about one.
    """
    if rows_proba is None:
        return None
    consts, coefs, columns, n_classes = rows_proba.constants

    def proba(feats: np.ndarray) -> np.ndarray:
        out = np.zeros((len(feats), n_classes))
        _polynomial_rows(feats, consts, coefs, columns, out)
        return out

    probe = _probe_rows(camera)
    return proba if np.array_equal(proba(probe), np.array(rows_proba(probe.tolist()))) else None
