"""A cache of the classifiers the command line trains for one camera, keyed by what they depend on.

A camera outside the general model's range gets a model trained on the spot (a few seconds);
the same camera on the next run reuses it. The key is a SHA-256 over everything the trained
numbers depend on: the camera's fields (intrinsics, distortion, pose), the paper's Table 1
sizes, the source text of the training code (``detector/train``, the classifier, the class
table), the training seed and set size, and the versions of scikit-learn, numpy and scipy.
Change any of them and the key changes, so a stale model is never reused.

The folder is ``$CITYSIM_CACHE/models`` when that variable is set, else
``$XDG_CACHE_HOME/citysim/models`` (default ``~/.cache/citysim/models``). A model is written
to a temporary file and renamed into place, so two runs training the same camera at once
both end with a whole file.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path

from detector.camera import CameraModel
from detector.classes import TABLE1
from detector.classifier import DimensionalClassifier, ModelFileError, library_versions

_PACKAGE = Path(__file__).resolve().parent
#: the source files whose text decides a trained model's numbers
TRAINING_SOURCES = ("classifier.py", "classes.py", "camera.py", "features.py")


def cache_dir() -> Path:
    """The folder cached models live in (see the module docstring)."""
    root = os.environ.get("CITYSIM_CACHE")
    if root:
        return Path(root) / "models"
    xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(xdg) / "citysim" / "models"


def training_code_digest() -> str:
    """SHA-256 of the training code's source text (``detector/train/*.py`` and ``TRAINING_SOURCES``)."""
    digest = hashlib.sha256()
    files = sorted((_PACKAGE / "train").glob("*.py")) + [_PACKAGE / name for name in TRAINING_SOURCES]
    for path in files:
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def model_key(camera: CameraModel, seed: int, n_per_class: int) -> str:
    """The cache key of a model trained for ``camera`` with ``seed`` and ``n_per_class`` samples per class.

    ``name`` and ``fps`` are left out: they change no pixel of a silhouette.
    """
    fields = camera.model_dump(exclude={"name", "fps"})
    what = {
        "camera": fields,
        "table1": {cls: asdict(size) for cls, size in TABLE1.items()},
        "training_code": training_code_digest(),
        "seed": seed,
        "n_per_class": n_per_class,
        "libraries": {k: v for k, v in library_versions().items() if k != "python"},
    }
    return hashlib.sha256(json.dumps(what, sort_keys=True).encode()).hexdigest()[:32]


def cached_camera_model(camera: CameraModel, train: Callable[[CameraModel], DimensionalClassifier], *,
                        seed: int = 0, n_per_class: int) -> tuple[DimensionalClassifier, Path, bool]:
    """The model for ``camera``: from the cache, or ``train(camera)`` and stored there.

    Returns (model, its cache file, whether it was reused). A cached file that cannot be read
    (damaged, another scikit-learn) is trained again and replaced.
    """
    folder = cache_dir()
    path = folder / f"camera-{model_key(camera, seed, n_per_class)}.joblib"
    if path.is_file():
        try:
            return DimensionalClassifier.load(path), path, True
        except ModelFileError:
            pass
    model = train(camera)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=".camera-", suffix=".joblib", dir=folder)
        os.close(fd)
        try:
            model.save(tmp, training={"seed": seed, "n_per_class": n_per_class, "cameras": "cached camera model"})
            os.replace(tmp, path)
        finally:
            Path(tmp).unlink(missing_ok=True)
    except OSError:  # a read-only home: the run goes on, uncached
        return model, path, False
    return model, path, False
