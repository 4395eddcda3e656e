"""What one training sample is: the objects the classifier's training set is drawn from.

Targets are the paper's Table 1 classes, sizes uniform in its ranges
(``detector.classes.TABLE1``), as the articulated models of
``detector.train.shapes``. Noise is of two sorts: things a night camera really
sees move, drawn as models too so they are projected and measured like the
targets (``NOISE_SAMPLERS``), and the paper's feature vectors out of the
Table 1 ranges, drawn directly (``FEATURE_NOISE``).

Conventions: world frame x along the street, y across it, z up, metres; a
sampler places its object's ground footprint centre at (x, y) with heading
counter-clockwise from +x, and returns the model with its velocity (m/s,
world frame) for motion blur. Everything is drawn from the generator passed in.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from detector.camera import CameraModel
from detector.classes import TABLE1
from detector.train.shapes import (
    Shape,
    animal_shape,
    blob_shape,
    cyclist_shape,
    ground_spot_shape,
    group_shape,
    pedestrian_shape,
    vehicle_shape,
)

# ------------------------------------------------------------------ samplers
# A sampler draws one object of its kind at ground point (x, y) with the given
# heading and returns the model and its velocity (m/s, world frame) for blur.
Sampler = Callable[
    [np.random.Generator, CameraModel, float, float, float], tuple[Shape, np.ndarray]
]


def uniform(rng: np.random.Generator, lo_hi: tuple[float, float]) -> float:
    """One draw uniform in [lo, hi)."""
    return float(rng.uniform(*lo_hi))


def ground_velocity(heading_rad: float, speed_mps: float) -> np.ndarray:
    """World-frame velocity (3,) m/s of something moving on the ground along ``heading_rad``."""
    return np.array([math.cos(heading_rad), math.sin(heading_rad), 0.0]) * speed_mps


def _pedestrian(rng: np.random.Generator, cam: CameraModel, x: float, y: float, heading: float):
    size = TABLE1["pedestrian"].draw(rng)
    shape = pedestrian_shape(x, y, heading, *size, rng.uniform(0, 2 * math.pi))
    return shape, ground_velocity(heading, rng.uniform(0.5, 2.5))


def group_members(
    rng: np.random.Generator, total_width_m: float
) -> list[tuple[float, float, float, float, float, float]]:
    """2-4 walkers side by side whose outer edges span ``total_width_m``; members are
    (forward_m, left_m, width_m, height_m, step_m, gait_phase_rad)."""
    s = TABLE1["group"]
    n = int(rng.integers(2, 5))
    widths = rng.uniform(*TABLE1["pedestrian"].width_m, size=n)
    if widths.sum() > total_width_m:  # shoulder to shoulder: squeeze rather than overlap
        widths *= total_width_m / widths.sum()
    gap = (total_width_m - widths.sum()) / (n - 1)
    left_edges = -total_width_m / 2 + np.concatenate([[0.0], np.cumsum(widths[:-1] + gap)])
    centres = left_edges + widths / 2
    heights = rng.uniform(*s.height_m, size=n)
    steps = rng.uniform(*s.length_m, size=n)
    phases = rng.uniform(0, 2 * math.pi, size=n)
    forwards = rng.uniform(-0.1, 0.1, size=n)
    return [
        (float(f), float(c), float(w), float(h), float(st), float(p))
        for f, c, w, h, st, p in zip(forwards, centres, widths, heights, steps, phases, strict=True)
    ]


def _group(rng: np.random.Generator, cam: CameraModel, x: float, y: float, heading: float):
    members = group_members(rng, uniform(rng, TABLE1["group"].width_m))
    return group_shape(x, y, heading, members), ground_velocity(heading, rng.uniform(0.5, 1.8))


def _cyclist(rng: np.random.Generator, cam: CameraModel, x: float, y: float, heading: float):
    size = TABLE1["cyclist"].draw(rng)
    shape = cyclist_shape(x, y, heading, *size, rng.uniform(0, 2 * math.pi))
    return shape, ground_velocity(heading, rng.uniform(2.0, 8.0))


def _vehicle(rng: np.random.Generator, cam: CameraModel, x: float, y: float, heading: float):
    shape = vehicle_shape(x, y, heading, *TABLE1["vehicle"].draw(rng))
    return shape, ground_velocity(heading, rng.uniform(3.0, 16.7))


def _animal(rng: np.random.Generator, cam: CameraModel, x: float, y: float, heading: float):
    """A cat, fox or dog."""
    w, h, length = rng.uniform(0.12, 0.35), rng.uniform(0.2, 0.7), rng.uniform(0.3, 1.0)
    shape = animal_shape(x, y, heading, w, h, length, rng.uniform(0, 2 * math.pi))
    return shape, ground_velocity(heading, rng.uniform(0.3, 5.0))


def _ground_spot(rng: np.random.Generator, cam: CameraModel, x: float, y: float, heading: float):
    """A flashlight or headlight spot sliding over the road."""
    shape = ground_spot_shape(x, y, heading, rng.uniform(0.3, 2.0), rng.uniform(0.3, 3.0))
    return shape, ground_velocity(heading, rng.uniform(0.0, 16.7))


def _insect(rng: np.random.Generator, cam: CameraModel, x: float, y: float, heading: float):
    """A moth lit by the emitter, 0.1-1.5 m in front of the lens on a random ray, flying anywhere."""
    u, v = rng.uniform(0, cam.width_px), rng.uniform(0, cam.height_px)
    ray_cam = np.array([(u - cam.cx_px) / cam.fx_px, (v - cam.cy_px) / cam.fy_px, 1.0])
    ray_world = cam.rotation_world_to_cam.T @ ray_cam
    centre = cam.position_m + ray_world / np.linalg.norm(ray_world) * rng.uniform(0.1, 1.5)
    size = rng.uniform(0.005, 0.03)
    shape = blob_shape(centre[0], centre[1], heading, size, size, size, centre[2] - size / 2)
    direction = rng.normal(size=3)
    return shape, direction / np.linalg.norm(direction) * rng.uniform(0.2, 3.0)


def _foliage(rng: np.random.Generator, cam: CameraModel, x: float, y: float, heading: float):
    """A cluster of leaves swaying from a branch at 40-90 % of the pole height (a camera
    on a pole sees the crowns next to it from above)."""
    w, h, length = rng.uniform(0.1, 0.8, size=3)
    shape = blob_shape(x, y, heading, w, h, length, rng.uniform(0.4, 0.9) * cam.height_m)
    return shape, ground_velocity(heading, rng.uniform(0.0, 1.0))


TARGET_SAMPLERS: dict[str, Sampler] = {
    "pedestrian": _pedestrian,
    "group": _group,
    "cyclist": _cyclist,
    "vehicle": _vehicle,
}

#: Small or flat things a camera really sees move, rendered like the targets.
NOISE_SAMPLERS: dict[str, Sampler] = {
    "animal": _animal,
    "ground_spot": _ground_spot,
    "insect": _insect,
    "foliage": _foliage,
}


# The paper's noise: feature vectors out of the Table 1 ranges, drawn directly as
# (estimated width m, estimated height m). Margins keep them clear of what real
# targets project to (estimated heights of walkers reach ~2.7 m and of cars ~5.5 m
# under steep tilts, because depth adds to the image height).
def _too_small(rng: np.random.Generator) -> tuple[float, float]:
    return rng.uniform(0.05, 1.0), rng.uniform(0.05, 0.8)


def _too_flat(rng: np.random.Generator) -> tuple[float, float]:
    return rng.uniform(0.5, 8.0), rng.uniform(0.02, 0.5)


def _too_tall_thin(rng: np.random.Generator) -> tuple[float, float]:
    return rng.uniform(0.02, 0.3), rng.uniform(2.5, 8.0)


def _too_large(rng: np.random.Generator) -> tuple[float, float]:
    if rng.random() < 0.5:
        return rng.uniform(6.0, 15.0), rng.uniform(0.5, 10.0)
    return rng.uniform(0.5, 15.0), rng.uniform(6.0, 10.0)


FEATURE_NOISE: dict[str, Callable[[np.random.Generator], tuple[float, float]]] = {
    "too_small": _too_small,
    "too_flat": _too_flat,
    "too_tall_thin": _too_tall_thin,
    "too_large": _too_large,
}
