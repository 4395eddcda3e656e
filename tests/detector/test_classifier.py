"""The dimensional classifier: held-out target/noise error rates, the shipped model,
save/load, parameter checks and scikit-learn's estimator conventions."""

from __future__ import annotations

import joblib
import numpy as np
import pytest
import sklearn
from sklearn.metrics import confusion_matrix
from sklearn.utils.estimator_checks import estimator_checks_generator

from detector.classes import CLASSES, TARGET_CLASSES
from detector.classifier import DimensionalClassifier, ModelFileError
from detector.general_model import GENERAL_MODEL_PATH, default_model
from detector.train.fit import train_general_model
from detector.train.sets import make_training_samples, make_training_set


@pytest.fixture(scope="module")
def held_out():
    """Synthetic features from a seed no model was trained on."""
    return make_training_samples(400, np.random.default_rng(12345))


@pytest.fixture(scope="module")
def small_model() -> DimensionalClassifier:
    X, y = make_training_set(60, np.random.default_rng(4))
    return DimensionalClassifier().fit(X, y)


def test_general_model_target_vs_noise_rates(held_out) -> None:
    model = default_model()
    p_target = model.predict_target_proba(held_out.X)
    is_noise = held_out.y == "noise"
    false_positive_rate = np.mean(p_target[is_noise] >= 0.5)
    false_negative_rate = np.mean(p_target[~is_noise] < 0.5)
    predicted = model.predict(held_out.X)
    matrix = confusion_matrix(held_out.y, predicted, labels=list(CLASSES), normalize="true")
    print("\nheld-out confusion matrix (rows: true, columns: predicted), classes", CLASSES)
    print(np.array2string(matrix, precision=3, suppress_small=True))
    print(f"target vs noise: FPR {false_positive_rate:.3f}  FNR {false_negative_rate:.3f}")
    for kind in np.unique(held_out.kind[is_noise]):
        print(
            f"  noise kind {kind:14s} taken for a target: {np.mean(p_target[held_out.kind == kind] >= 0.5):.3f}"
        )
    assert false_positive_rate <= 0.05
    assert false_negative_rate <= 0.10
    # vehicles stand apart (paper section 5.4); every target class is mostly found as itself
    assert matrix[4, 4] > 0.8
    assert np.all(np.diag(matrix)[1:] > 0.5)


def test_shipped_model_is_what_the_code_trains(held_out) -> None:
    """The shipped file behaves as a fresh training does, within what another CPU changes.

    The optimiser stops once its gradient is small, and another machine's BLAS sums in
    another order, so it stops at a slightly different point of a flat optimum: measured
    across CPUs, probabilities moved by up to 0.049 while the class only changed for points
    sitting on a decision boundary. So: the same class on >= 99.5% of a held-out set, no
    probability off by more than 0.10 (twice the largest move seen), and a mean move under
    0.01 (a model trained on other data moves it by several times that; see below).
    """
    shipped = DimensionalClassifier.load(GENERAL_MODEL_PATH)
    fresh = train_general_model(seed=0)
    same_class = np.mean(shipped.predict(held_out.X) == fresh.predict(held_out.X))
    moved = np.abs(shipped.predict_proba(held_out.X) - fresh.predict_proba(held_out.X))
    print(f"\nsame class {same_class:.4f}, probability moved max {moved.max():.4f} mean {moved.mean():.5f}")
    assert same_class >= 0.995
    assert moved.max() <= 0.10
    assert moved.mean() <= 0.01
    # the tolerance can fail: a model trained on another seed does not pass it
    other = train_general_model(seed=1, n_per_class=200)
    assert np.abs(shipped.predict_proba(held_out.X) - other.predict_proba(held_out.X)).mean() > 0.01
    assert default_model() is default_model()  # cached per process


def test_shipped_model_records_how_it_was_trained() -> None:
    made = DimensionalClassifier.provenance(GENERAL_MODEL_PATH)
    assert made["training"]["seed"] == 0
    assert made["training"]["n_per_class"] > 0
    assert {"numpy", "scipy", "scikit-learn", "python"} <= set(made["library_versions"])


def test_probabilities_follow_classes_order(small_model, held_out) -> None:
    assert tuple(small_model.classes_) == CLASSES and TARGET_CLASSES == CLASSES[1:]
    proba = small_model.predict_proba(held_out.X[:50])
    assert proba.shape == (50, 5) and np.allclose(proba.sum(axis=1), 1.0)
    assert np.array_equal(
        small_model.predict(held_out.X[:50]), np.array(CLASSES, dtype=object)[proba.argmax(axis=1)]
    )
    assert np.allclose(small_model.predict_target_proba(held_out.X[:50]), 1.0 - proba[:, 0])


def test_missing_classes_keep_their_columns(held_out) -> None:
    keep = np.isin(held_out.y, ["noise", "pedestrian", "vehicle"])
    model = DimensionalClassifier().fit(held_out.X[keep], held_out.y[keep])
    proba = model.predict_proba(held_out.X[:20])
    assert tuple(model.classes_) == CLASSES
    assert np.all(proba[:, [2, 3]] == 0.0) and np.allclose(proba.sum(axis=1), 1.0)


def test_save_load_round_trip(small_model, held_out, tmp_path) -> None:
    path = small_model.save(tmp_path / "sub" / "model.joblib")
    loaded = DimensionalClassifier.load(path)
    assert np.array_equal(loaded.predict_proba(held_out.X), small_model.predict_proba(held_out.X))
    assert np.array_equal(loaded.predict(held_out.X), small_model.predict(held_out.X))


def test_unusable_model_files_are_named(small_model, tmp_path) -> None:
    missing = tmp_path / "nope.joblib"
    with pytest.raises(ModelFileError, match=f"{missing}: model file not found"):
        DimensionalClassifier.load(missing)
    corrupt = tmp_path / "corrupt.joblib"
    corrupt.write_bytes(b"\x80\x04 this is not a pickle")
    with pytest.raises(ModelFileError, match=f"{corrupt}: not a readable model file"):
        DimensionalClassifier.load(corrupt)
    foreign = tmp_path / "foreign.joblib"
    joblib.dump({"weights": [1, 2, 3]}, foreign)
    with pytest.raises(ModelFileError, match=f"{foreign}: not a DimensionalClassifier file"):
        DimensionalClassifier.load(foreign)
    old = tmp_path / "old.joblib"
    joblib.dump({"format": 1, "sklearn_version": "0.24.2", "model": small_model}, old)
    with pytest.raises(
        ModelFileError, match=f"{old}: written by scikit-learn 0.24.2, but {sklearn.__version__}"
    ):
        DimensionalClassifier.load(old)


@pytest.mark.parametrize(
    ("params", "message"),
    [
        ({"C": -1.0}, r"parameter C must be a finite float > 0, got -1.0"),
        ({"C": float("inf")}, r"parameter C must be a finite float > 0, got inf"),
        (
            {"solver": "liblinear"},
            r"parameter solver must be one of \['newton-cg'.*got 'liblinear'",
        ),
        ({"max_iter": 0}, r"parameter max_iter must be an integer >= 1, got 0"),
    ],
)
def test_bad_parameters_are_named(params, message, held_out) -> None:
    with pytest.raises(ValueError, match=message):
        DimensionalClassifier(**params).fit(held_out.X[:100], held_out.y[:100])


# Two of scikit-learn's checks exercise optional packages this project does not
# install (pandas, the array API); every other check runs.
_NEEDS_ABSENT_PACKAGES = {"check_array_api_input", "check_classifier_data_not_an_array"}
_SKLEARN_CHECKS = [
    (est, check)
    for est, check in estimator_checks_generator(DimensionalClassifier(), legacy=True, mark=None)
    if getattr(check, "func", check).__name__ not in _NEEDS_ABSENT_PACKAGES
]


@pytest.mark.parametrize(
    ("estimator", "check"),
    _SKLEARN_CHECKS,
    ids=[getattr(c, "func", c).__name__ for _, c in _SKLEARN_CHECKS],
)
def test_sklearn_estimator_checks(estimator, check) -> None:
    check(estimator)


def test_camera_rows_proba_equals_predict_proba(small_model, held_out) -> None:
    from detector.camera import CameraModel
    from detector.fast_proba import camera_rows_proba

    cam = CameraModel(
        height_m=4.5,
        tilt_deg=17.0,
        focal_mm=3.67,
        sensor_w_mm=4.8,
        sensor_h_mm=3.6,
        width_px=424,
        height_px=240,
    )
    for model in (default_model(), small_model):
        rows_proba = camera_rows_proba(model, cam)
        assert rows_proba is not None
        X = held_out.X.copy()
        X[:, 4], X[:, 5] = cam.tilt_deg, cam.height_m  # one camera's rows
        got = np.array(rows_proba(X.tolist()))
        np.testing.assert_allclose(got, model.predict_proba(X), rtol=0, atol=1e-9)
    # a model missing classes keeps zero columns for them
    keep = np.isin(held_out.y, ["noise", "vehicle"])
    two = DimensionalClassifier().fit(held_out.X[keep], held_out.y[keep])
    got = np.array(camera_rows_proba(two, cam)(X[:30].tolist()))
    np.testing.assert_allclose(got, two.predict_proba(X[:30]), rtol=0, atol=1e-9)
    assert np.all(got[:, [1, 2, 3]] == 0.0)
    # anything but the known pipeline: no fast path
    from sklearn.linear_model import LogisticRegression

    other = LogisticRegression(max_iter=5000).fit(held_out.X[::20], held_out.y[::20])
    assert camera_rows_proba(other, cam) is None


def test_compiled_rows_proba_equals_the_plain_python_rows_bit_for_bit(small_model, held_out) -> None:
    from detector.camera import CameraModel
    from detector.fast_proba import camera_rows_proba, compiled_rows_proba

    cam = CameraModel(
        height_m=4.5, tilt_deg=17.0, focal_mm=3.67, sensor_w_mm=4.8, sensor_h_mm=3.6, width_px=424, height_px=240
    )
    keep = np.isin(held_out.y, ["noise", "vehicle"])
    two = DimensionalClassifier().fit(held_out.X[keep], held_out.y[keep])  # one logistic output
    rng = np.random.default_rng(5)
    for model in (default_model(), small_model, two):
        rows_proba = camera_rows_proba(model, cam)
        compiled = compiled_rows_proba(rows_proba, cam)
        assert compiled is not None
        X = np.vstack([held_out.X, rng.uniform((0, -2, 0, 0, 0, 0), (15, 15, 60, 200, 0, 0), (5000, 6))])
        X[:, 4], X[:, 5] = cam.tilt_deg, cam.height_m  # one camera's rows
        assert np.array_equal(compiled(X), np.array(rows_proba(X.tolist())))
    assert compiled_rows_proba(None, cam) is None
