"""Fitting the dimensional classifier on synthetic features: the general model and per-camera models.

``python -m detector train`` writes either to a file; the shipped
``detector/models/general.joblib`` is ``train_general_model(seed=0)``.
"""

from __future__ import annotations

import numpy as np

from detector.camera import CameraModel
from detector.classifier import DimensionalClassifier
from detector.train.sets import make_training_set

#: Samples per class of the default general model: enough for stable rates, trains in a few seconds.
DEFAULT_N_PER_CLASS = 800


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
