"""The dimensional classifier (paper section 5.4): degree-2 polynomial logistic regression.

``DimensionalClassifier`` is a scikit-learn estimator wrapping the Pipeline

    StandardScaler -> PolynomialFeatures(2) -> LogisticRegression(newton-cg, C=3)

over the six features of ``detector.features.FEATURE_NAMES`` (width m,
height m, contour area m^2, distance m, camera tilt deg, camera height m). The
quadratic terms give the paper's "circular decision boundary" around each
class. When every training label is one of ``CLASSES`` the fitted ``classes_``
is ``CLASSES`` in that order, so ``predict_proba`` columns line up with it;
any other labels behave like any scikit-learn classifier (sorted unique labels).

The general model the detector runs by default is ``detector.general_model``'s;
training sets and training live in ``detector.train``, the plain-Python
evaluation the detector uses per frame in ``detector.fast_proba``. The shipped
model file pickles this module's ``DimensionalClassifier``, so the class stays here.
"""

from __future__ import annotations

import numbers
import warnings
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

from detector.classes import CLASSES

SOLVERS = ("newton-cg", "lbfgs", "newton-cholesky", "sag", "saga")
MODEL_FORMAT = 1


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
