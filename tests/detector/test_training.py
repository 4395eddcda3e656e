"""Synthetic training features: deterministic, shaped like the detector's regions,
related to the Table 1 sizes, specialisable to one camera, loud on bad input."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from detector.camera import CameraModel
from detector.classes import CLASSES
from detector.features import FEATURE_NAMES
from detector.train.config import TrainingConfig
from detector.train.regions import shape_region
from detector.train.samplers import FEATURE_NOISE, NOISE_SAMPLERS
from detector.train.sets import make_training_samples, make_training_set
from detector.train.shapes import pedestrian_shape
from tests.detector.cameras import scene_b

SCENE_B = scene_b()
COL = {name: i for i, name in enumerate(FEATURE_NAMES)}


@pytest.fixture(scope="module")
def small_set():
    return make_training_samples(40, np.random.default_rng(7))


def test_same_seed_same_arrays_bit_for_bit(small_set) -> None:
    X, y = make_training_set(40, np.random.default_rng(7))
    assert np.array_equal(X, small_set.X) and np.array_equal(y, small_set.y)
    X2, _ = make_training_set(40, np.random.default_rng(8))
    assert X2.shape == X.shape and not np.allclose(X2, X)


def test_rows_per_class_and_feature_ranges(small_set) -> None:
    X, y, kind = small_set.X, small_set.y, small_set.kind
    config = TrainingConfig()
    total_weight = sum(config.noise_weights.values())
    for noise_kind, weight in config.noise_weights.items():  # one quota per kind
        assert np.sum(kind == noise_kind) == round(
            config.noise_ratio * 4 * 40 * weight / total_weight
        )
    assert np.all(y[np.isin(kind, list(config.noise_weights))] == "noise")
    assert set(y) == set(CLASSES) and X.shape[1] == 6
    for cls in CLASSES[1:]:
        assert np.sum(y == cls) == 40 and np.all(kind[y == cls] == cls)
    assert abs(np.sum(y == "noise") - config.noise_ratio * 4 * 40) <= len(config.noise_weights)
    assert np.all(np.isfinite(X))
    assert np.all((X[:, COL["distance_m"]] > 0) & (X[:, COL["distance_m"]] <= 50.0))
    assert np.all((X[:, COL["tilt_deg"]] >= 0) & (X[:, COL["tilt_deg"]] <= 80.0))
    assert np.all((X[:, COL["camera_height_m"]] >= 2) & (X[:, COL["camera_height_m"]] <= 10.0))
    rendered = ~np.isin(kind, list(FEATURE_NOISE))
    w, h, a = X[rendered, 0], X[rendered, 1], X[rendered, 2]
    # the contour area comes from the silhouette: never more than the box, usually much less
    assert np.all(a <= w * h * (1 + 1e-9)) and np.median(a / (w * h)) < 0.8


def test_features_follow_table1_sizes(small_set) -> None:
    X, y = small_set.X, small_set.y
    median = {cls: np.median(X[y == cls], axis=0) for cls in CLASSES[1:]}
    # walkers are estimated about their real height (1.15-2 m, plus what depth adds seen from above)
    assert 1.2 < median["pedestrian"][COL["height_m"]] < 2.6
    assert median["pedestrian"][COL["width_m"]] < median["group"][COL["width_m"]]
    assert median["vehicle"][COL["area_m2"]] > 2 * median["pedestrian"][COL["area_m2"]]
    assert median["vehicle"][COL["width_m"]] > 1.4


def test_specialised_to_given_camera() -> None:
    placed = SCENE_B.placed(
        x_m=12.0, y_m=-3.0, yaw_deg=40.0
    )  # the pose on the street does not matter
    X, y = make_training_set(15, np.random.default_rng(3), cameras=[placed])
    assert np.all(X[:, COL["tilt_deg"]] == 22.0) and np.all(X[:, COL["camera_height_m"]] == 3.1)
    X2, _ = make_training_set(15, np.random.default_rng(3), cameras=[SCENE_B])
    assert np.allclose(X, X2)


def test_region_uses_silhouette_area_and_drops_border_objects() -> None:
    config = TrainingConfig(jitter_px=0)
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3))
    still = np.zeros(3)
    walker = pedestrian_shape(8.0, 0.0, math.pi / 2, 0.5, 1.75, 0.7, math.pi / 2)
    box, area = shape_region(SCENE_B, walker, still, 0.0, config, kernel)
    assert 0.3 * box[2] * box[3] < area < 0.8 * box[2] * box[3]
    # motion blur along the heading widens the box
    blurred, _ = shape_region(SCENE_B, walker, np.array([0.0, 10.0, 0.0]), 0.04, config, kernel)
    assert blurred[2] > box[2] + 3
    near_edge = pedestrian_shape(3.0, 0.0, 0.0, 0.5, 1.75, 0.7, 0.0)  # feet below the bottom row
    assert shape_region(SCENE_B, near_edge, still, 0.0, config, kernel) is None


def test_bad_input_is_named() -> None:
    with pytest.raises(ValueError, match="n_per_class must be an integer >= 1, got 0"):
        make_training_set(0, np.random.default_rng(0))
    with pytest.raises(ValueError, match=r"noise_weights must map kinds in .*got \{'bats': 1.0\}"):
        TrainingConfig(noise_weights={"bats": 1.0})
    with pytest.raises(
        ValueError, match=r"tilt_deg must be \(min, max\) with min <= max, got \(50, 10\)"
    ):
        TrainingConfig(tilt_deg=(50, 10))
    with pytest.raises(ValueError, match="at least one CameraModel"):
        make_training_set(5, np.random.default_rng(0), cameras=[])


def test_unseeable_kind_fails_instead_of_looping() -> None:
    # a 2 m pole looking nearly straight down never sees a whole walker or car
    steep = CameraModel(
        height_m=2.0,
        tilt_deg=80.0,
        focal_mm=3.67,
        sensor_w_mm=4.8,
        sensor_h_mm=3.6,
        width_px=424,
        height_px=240,
    )
    config = TrainingConfig(noise_weights={"too_small": 1.0})
    with pytest.raises(
        RuntimeError,
        match=r"saw '(pedestrian|group|cyclist|vehicle)' whole in only 0 of \d+ attempts",
    ):
        make_training_set(1, np.random.default_rng(0), cameras=[steep], config=config)


def test_every_noise_kind_is_registered() -> None:
    assert set(TrainingConfig().noise_weights) <= set(NOISE_SAMPLERS) | set(FEATURE_NOISE)
    assert not set(NOISE_SAMPLERS) & set(FEATURE_NOISE)


def test_region_limits_are_the_segmenters_and_cameras_the_general_models() -> None:
    import detector.classes as classes
    from detector.segment import SegmenterParams
    from detector.train.samplers import TARGET_SAMPLERS

    config, segmenter = TrainingConfig(), SegmenterParams()
    for name in ("open_kernel_px", "dilate_iterations", "min_area_fraction", "min_extent"):
        assert getattr(config, name) == getattr(segmenter, name), name
    # the runtime tells whether a camera is like the general model's from the same constants
    assert config.camera_height_m == classes.GENERAL_CAMERA_HEIGHT_M
    assert config.tilt_deg == classes.GENERAL_TILT_DEG
    assert config.min_view_range_m == classes.GENERAL_MIN_VIEW_RANGE_M
    # targets in CLASSES order: make_training_set's rows follow it
    assert tuple(TARGET_SAMPLERS) == classes.TARGET_CLASSES == tuple(classes.TABLE1)


def test_cli_train_names_the_camera_file_that_never_sees_an_object_whole(tmp_path, capsys) -> None:
    from detector.__main__ import main

    camera_file = tmp_path / "steep.yaml"
    camera_file.write_text(
        "height_m: 2.0\ntilt_deg: 80.0\nfocal_mm: 3.67\nsensor_w_mm: 4.8\nsensor_h_mm: 3.6\n"
        "width_px: 424\nheight_px: 240\n"
    )
    out = tmp_path / "models" / "steep.joblib"
    assert main(["train", "--camera", str(camera_file), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert err.startswith(f"error: {camera_file}: this camera never sees a whole ")
    assert "(0 of 2000 tries)" in err and "height_m, tilt_deg" in err
    assert not out.parent.exists()  # nothing half-written
