"""The dimensional classifier (paper section 5.4): degree-2 polynomial logistic regression.

``DimensionalClassifier`` is a scikit-learn estimator wrapping the Pipeline

    StandardScaler -> PolynomialFeatures(2) -> LogisticRegression(newton-cg, C=3)

over the six features of ``detector.features.FEATURE_NAMES`` (width m,
height m, contour area m^2, distance m, camera tilt deg, camera height m). The
quadratic terms give the paper's "circular decision boundary" around each
class. When every training label is one of ``CLASSES`` the fitted ``classes_``
is ``CLASSES`` in that order, so ``predict_proba`` columns line up with it;
any other labels behave like any scikit-learn classifier (sorted unique labels).

``default_model()`` gives the general model (trained on random cameras,
seed 0): loaded from ``detector/models/general.joblib`` when that file was
written by the installed scikit-learn, trained afresh otherwise.
"""

from __future__ import annotations

import functools
import math
import numbers
import operator
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import joblib
import numpy as np
import sklearn
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.exceptions import InconsistentVersionWarning
from sklearn.linear_model import LogisticRegression
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import PolynomialFeatures, StandardScaler
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data
from threadpoolctl import threadpool_limits

from detector.camera import CameraModel
from detector.features import FEATURE_NAMES, N_FEATURES
from detector.training import CLASSES, make_training_set

TARGET_CLASSES = CLASSES[1:]
SOLVERS = ("newton-cg", "lbfgs", "newton-cholesky", "sag", "saga")
MODEL_FORMAT = 1
#: Samples per class of the default general model: enough for stable rates, trains in a few seconds.
DEFAULT_N_PER_CLASS = 800
GENERAL_MODEL_PATH = Path(__file__).parent / "models" / "general.joblib"
# one camera's regions all share these two features; the rest vary per region
_TILT_COLUMN = FEATURE_NAMES.index("tilt_deg")
_HEIGHT_COLUMN = FEATURE_NAMES.index("camera_height_m")
_FREE_COLUMNS = tuple(i for i in range(N_FEATURES) if i not in (_TILT_COLUMN, _HEIGHT_COLUMN))


class ModelFileError(ValueError):
    """A model file that is missing, unreadable or written by another version; names the file."""


class DimensionalClassifier(ClassifierMixin, BaseEstimator):
    """Degree-2 polynomial logistic regression on dimensional features.

    Parameters
    ----------
    C : float > 0
        Inverse L2 regularisation strength of the logistic regression.
    solver : one of SOLVERS
        Logistic-regression solver (the paper's model uses Newton-CG).
    max_iter : int >= 1
        Solver iteration limit.
    """

    def __init__(self, C: float = 3.0, solver: str = "newton-cg", max_iter: int = 500) -> None:
        self.C = C
        self.solver = solver
        self.max_iter = max_iter

    def _check_params(self) -> None:
        name = type(self).__name__
        c_ok = (
            isinstance(self.C, numbers.Real)
            and not isinstance(self.C, bool)
            and 0 < self.C < np.inf
        )
        if not c_ok:
            raise ValueError(f"{name}: parameter C must be a finite float > 0, got {self.C!r}")
        if self.solver not in SOLVERS:
            raise ValueError(
                f"{name}: parameter solver must be one of {list(SOLVERS)}, got {self.solver!r}"
            )
        it_ok = (
            isinstance(self.max_iter, numbers.Integral)
            and not isinstance(self.max_iter, bool)
            and self.max_iter >= 1
        )
        if not it_ok:
            raise ValueError(
                f"{name}: parameter max_iter must be an integer >= 1, got {self.max_iter!r}"
            )

    def fit(self, X: np.ndarray, y: np.ndarray) -> DimensionalClassifier:
        """Fit on X (N, n_features) float and y (N,) class labels; returns self."""
        self._check_params()
        X, y = validate_data(self, X, y, dtype=np.float64)
        check_classification_targets(y)
        labels = np.unique(y)
        if len(labels) < 2:
            raise ValueError(
                f"{type(self).__name__}.fit needs at least 2 classes in y, got 1 class: {labels.tolist()}"
            )
        if y.dtype.kind in "OUS" and set(labels.tolist()) <= set(CLASSES):
            self.classes_ = np.array(CLASSES, dtype=object)
        else:
            self.classes_ = labels
        codes = np.searchsorted(labels, y)
        # map each label to its column in classes_ so the pipeline's classes are column indices
        column_of_label = np.array([np.flatnonzero(self.classes_ == lab)[0] for lab in labels])
        self.pipeline_ = Pipeline(
            [
                ("scale", StandardScaler()),
                ("poly", PolynomialFeatures(degree=2, include_bias=False)),
                (
                    "logreg",
                    LogisticRegression(
                        C=float(self.C), solver=self.solver, max_iter=int(self.max_iter)
                    ),
                ),
            ]
        )
        # the problem is small (N x 27 terms): threaded BLAS only adds contention (5x slower on a busy 2-core box)
        with threadpool_limits(limits=1):
            self.pipeline_.fit(X, column_of_label[codes])
        self.n_iter_ = self.pipeline_[-1].n_iter_
        self.sklearn_version_ = sklearn.__version__
        return self

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """Class probabilities (N, len(classes_)); columns in ``classes_`` order (CLASSES for the detector)."""
        check_is_fitted(self, "pipeline_")
        X = validate_data(self, X, dtype=np.float64, reset=False)
        seen = self.pipeline_.classes_  # column indices present in the training labels
        proba = np.zeros((len(X), len(self.classes_)))
        proba[:, seen] = self.pipeline_.predict_proba(X)
        return proba

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Most probable label per row (N,)."""
        check_is_fitted(self, "pipeline_")
        return self.classes_[np.argmax(self.predict_proba(X), axis=1)]

    def predict_target_proba(self, X: np.ndarray) -> np.ndarray:
        """P(any target class) = 1 - P(noise), (N,)."""
        check_is_fitted(self, "pipeline_")
        if "noise" not in self.classes_:
            raise ValueError(
                f"{type(self).__name__}.predict_target_proba needs a model trained with a 'noise' class"
            )
        noise_col = int(np.flatnonzero(self.classes_ == "noise")[0])
        return 1.0 - self.predict_proba(X)[:, noise_col]

    # ---------------------------------------------------------------- files
    def save(self, path: str | Path, training: dict | None = None) -> Path:
        """Write the fitted model to ``path`` with how it was made: ``training`` (e.g. seed,
        samples per class, camera) and the library versions that trained it, so a model that
        behaves differently elsewhere can be traced to its optimiser's numbers."""
        check_is_fitted(self, "pipeline_")
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        joblib.dump(
            {
                "format": MODEL_FORMAT,
                "sklearn_version": sklearn.__version__,
                "training": dict(training or {}),
                "library_versions": library_versions(),
                "model": self,
            },
            path,
            compress=3,
        )
        return path

    @staticmethod
    def provenance(path: str | Path) -> dict:
        """What a model file says about its training: ``training`` and ``library_versions``."""
        data = joblib.load(path)
        return {"training": data.get("training", {}), "library_versions": data.get("library_versions", {})}

    @classmethod
    def load(cls, path: str | Path) -> DimensionalClassifier:
        """Read a model written by ``save``; ModelFileError naming the file if it cannot be used."""
        path = Path(path)
        if not path.is_file():
            raise ModelFileError(f"{path}: model file not found")
        try:
            with warnings.catch_warnings():
                # a version mismatch is reported below, in our own words
                warnings.simplefilter("ignore", InconsistentVersionWarning)
                data = joblib.load(path)
        except Exception as exc:  # joblib/pickle raise many kinds on a damaged file
            raise ModelFileError(
                f"{path}: not a readable model file ({type(exc).__name__}: {exc})"
            ) from None
        if (
            not isinstance(data, dict)
            or data.get("format") != MODEL_FORMAT
            or not isinstance(data.get("model"), cls)
        ):
            raise ModelFileError(
                f"{path}: not a {cls.__name__} file (expected format {MODEL_FORMAT} written by save())"
            )
        if data["sklearn_version"] != sklearn.__version__:
            raise ModelFileError(
                f"{path}: written by scikit-learn {data['sklearn_version']}, but {sklearn.__version__} is installed; "
                "retrain it (python -m detector train)"
            )
        return data["model"]


def library_versions() -> dict[str, str]:
    """Versions of what decides a fitted model's numbers (the optimiser runs on numpy/scipy BLAS)."""
    import platform

    import scipy

    return {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "scikit-learn": sklearn.__version__,
        "machine": platform.machine(),
    }


def train_general_model(
    seed: int = 0, n_per_class: int = DEFAULT_N_PER_CLASS
) -> DimensionalClassifier:
    """The general model: random Table 2 cameras at 2-10 m and 0-80 deg (height and tilt are features)."""
    X, y = make_training_set(n_per_class, np.random.default_rng(seed))
    return DimensionalClassifier().fit(X, y)


def train_camera_model(
    camera: CameraModel, seed: int = 0, n_per_class: int = DEFAULT_N_PER_CLASS
) -> DimensionalClassifier:
    """A model specialised to one installed camera (its intrinsics, height and tilt)."""
    X, y = make_training_set(n_per_class, np.random.default_rng(seed), cameras=[camera])
    return DimensionalClassifier().fit(X, y)


@functools.cache
def default_model() -> DimensionalClassifier:
    """The general model, once per process: the shipped file if usable, else trained (seed 0)."""
    try:
        return DimensionalClassifier.load(GENERAL_MODEL_PATH)
    except ModelFileError:
        return train_general_model(seed=0)


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

    return proba_rows if _agrees(proba, model, camera) else None
