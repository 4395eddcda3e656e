"""The paper's detector (Matveev et al., Sensors 2020): background subtraction,
pinhole-geometry features and a degree-2 polynomial logistic regression.

Stands alone: it never imports ``citysim``. The runtime (camera, video, segment,
divide, features, classifier, detector, ...) never imports the training code either,
which lives in ``detector.train``; ``detector.classes`` holds what both share.
"""

from detector.camera import CameraError, CameraModel, NoGroundPointError

__all__ = ["CameraModel", "CameraError", "NoGroundPointError"]
__version__ = "0.1.0"
