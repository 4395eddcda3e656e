"""The runtime stays apart from training: a lamp that imports the detector and runs the
shipped model loads nothing of ``detector.train``."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def loaded_train_modules(code: str) -> str:
    """Run ``code`` in a fresh interpreter, then print the detector.train modules it loaded."""
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]),
    }
    probe = code + "\nimport sys; print([m for m in sys.modules if m.startswith('detector.train')])"
    result = subprocess.run(
        [sys.executable, "-c", probe], cwd=REPO, env=env, capture_output=True, text=True, check=True
    )
    return result.stdout.strip().splitlines()[-1]


def test_importing_the_detector_loads_no_training_code() -> None:
    assert loaded_train_modules("import detector.detector") == "[]"


def test_the_shipped_model_and_the_cli_load_no_training_code() -> None:
    code = (
        "import detector.detector, detector.__main__ as cli\n"
        "from detector.general_model import default_model\n"
        "from tests.detector.cameras import scene_b\n"
        "model = default_model()\n"
        "assert type(model).__module__ == 'detector.classifier', type(model)\n"
        "assert cli.general_model_covers(scene_b())\n"
        "detector.detector.Detector(scene_b())"
    )
    assert loaded_train_modules(code) == "[]"


def test_the_shipped_model_still_loads_from_its_pickle() -> None:
    # the file pickles detector.classifier.DimensionalClassifier: that class must stay there
    from detector.classifier import DimensionalClassifier
    from detector.general_model import GENERAL_MODEL_PATH

    model = DimensionalClassifier.load(GENERAL_MODEL_PATH)
    assert tuple(model.classes_) == ("noise", "pedestrian", "group", "cyclist", "vehicle")
