"""What the classifier tells apart and what it was trained on: the class names, their sizes
(the paper's Table 1) and the range of cameras the general model covers.

The runtime, the training code (``detector.train``) and the simulator all read these
from here, so each number lives in one place; importing this module loads no training code.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: The classifier's classes, in the order of its probability columns.
CLASSES = ("noise", "pedestrian", "group", "cyclist", "vehicle")
#: The classes a lamp reacts to: everything but noise.
TARGET_CLASSES = CLASSES[1:]


@dataclass(frozen=True)
class SizeRange:
    """One row of the paper's Table 1: (min, max) sizes of an object of a class, in metres.

    ``width_m`` across the direction of motion, ``height_m`` above the ground,
    ``length_m`` along the direction of motion (Table 1's "depth": step length for
    walkers, bicycle length for cyclists, car length for vehicles).
    """

    width_m: tuple[float, float]
    height_m: tuple[float, float]
    length_m: tuple[float, float]

    def draw(self, rng: np.random.Generator) -> tuple[float, float, float]:
        """One (width, height, length) in metres, each uniform in its range, drawn in that order."""
        width_m = float(rng.uniform(*self.width_m))
        height_m = float(rng.uniform(*self.height_m))
        length_m = float(rng.uniform(*self.length_m))
        return width_m, height_m, length_m


#: The paper's Table 1, metres, for each target class.
TABLE1: dict[str, SizeRange] = {
    "pedestrian": SizeRange((0.3, 0.64), (1.15, 2.0), (0.3, 0.79)),
    "group": SizeRange((1.2, 3.0), (1.5, 2.0), (0.3, 0.79)),
    "cyclist": SizeRange((0.3, 0.64), (1.5, 1.9), (1.5, 1.7)),
    "vehicle": SizeRange((1.4, 1.8), (1.4, 2.0), (3.7, 4.6)),
}

# The general model's cameras: poles 2-10 m high tilted 0-80 deg down (the paper's Table 2
# installations), seeing the ground at least 25 m ahead (the paper's detection range).
# Training draws its random cameras in these ranges; the CLI uses them to tell whether a
# camera is like those the shipped model knows.
GENERAL_CAMERA_HEIGHT_M = (2.0, 10.0)
GENERAL_TILT_DEG = (0.0, 80.0)
GENERAL_MIN_VIEW_RANGE_M = 25.0
