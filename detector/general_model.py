"""The general model the detector runs when given none: the shipped file, else the same model
trained afresh.

``detector/models/general.joblib`` is ``train_general_model(seed=0)`` (random
Table 2 cameras, ``detector.classes``' ``GENERAL_*`` ranges). When the installed
scikit-learn cannot use that file, the model is trained again with the same seed
(a few seconds); only then is the training code (``detector.train``) imported, so
a lamp running the shipped model never loads it.
"""

from __future__ import annotations

import functools
from pathlib import Path

from detector.classifier import DimensionalClassifier, ModelFileError

GENERAL_MODEL_PATH = Path(__file__).parent / "models" / "general.joblib"
#: The training seed of the shipped model, and of the model trained when it cannot be loaded.
GENERAL_MODEL_SEED = 0


@functools.cache
def default_model() -> DimensionalClassifier:
    """The general model, once per process: the shipped file if usable, else trained (seed 0)."""
    try:
        return DimensionalClassifier.load(GENERAL_MODEL_PATH)
    except ModelFileError:
        # imported here, not at the top: the training code loads only when the file is unusable
        from detector.train.fit import train_general_model

        return train_general_model(seed=GENERAL_MODEL_SEED)
