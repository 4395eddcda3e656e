"""The convex parts the 3D models of ``detector.train.shapes`` are built from, and the ``Shape`` they make.

Conventions: a part is a convex solid given by ``VERTICES_PER_PART`` (8)
vertices; helpers build parts in a model's local frame (forward f along the
heading, left l, up z; metres) and ``Parts.place`` turns them into world
vertices (x along the street, y across it, z up) for a model at (x_m, y_m)
heading ``heading_rad`` counter-clockwise from +x. Each part kind has a
near-infrared reflectance for the renderer.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

VERTICES_PER_PART = 8

# Near-infrared reflectances (0..1) by part kind: fabric and paint reflect
# NIR well, skin less, rubber and glass little.
IR_REFLECTANCE = {
    "head": 0.35,
    "torso": 0.55,
    "arm": 0.5,
    "leg": 0.45,
    "frame": 0.4,
    "handlebar": 0.3,
    "wheel": 0.12,
    "body": 0.6,
    "cabin": 0.25,
    "tail": 0.3,
    "spot": 0.9,
}


@dataclass(frozen=True)
class Shape:
    """A model as P convex parts: ``corners_m`` (P, 8, 3) world vertices, m."""

    corners_m: np.ndarray
    ir_reflectance: np.ndarray
    part_kind: tuple[str, ...]

    def __post_init__(self) -> None:
        if self.corners_m.ndim != 3 or self.corners_m.shape[2] != 3:
            raise ValueError(
                f"Shape.corners_m must have shape (P, K, 3), got {self.corners_m.shape}"
            )
        if not (len(self.ir_reflectance) == len(self.part_kind) == len(self.corners_m)):
            raise ValueError(
                f"Shape needs one ir_reflectance and part_kind per part: {len(self.corners_m)} parts, "
                f"{len(self.ir_reflectance)} reflectances, {len(self.part_kind)} kinds"
            )

    @property
    def n_parts(self) -> int:
        return len(self.corners_m)

    def extents_m(self, heading_rad: float) -> tuple[float, float, float]:
        """(length along heading, width across it, height) of the vertex cloud, m."""
        pts = self.corners_m.reshape(-1, 3)
        fwd = np.array([math.cos(heading_rad), math.sin(heading_rad)])
        left = np.array([-fwd[1], fwd[0]])
        f, lat = pts[:, :2] @ fwd, pts[:, :2] @ left
        return (
            float(np.ptp(f)),
            float(np.ptp(lat)),
            float(pts[:, 2].max() - min(0.0, pts[:, 2].min())),
        )


# ----------------------------------------------------------------- part helpers
# Parts are first built in the model's local frame (forward f, left l, up z),
# then placed; ``Parts`` collects them in order.


class Parts:
    """An ordered list of convex parts in a model's local frame; ``place`` makes the Shape."""

    def __init__(self) -> None:
        self.corners: list[np.ndarray] = []
        self.kinds: list[str] = []

    def add(self, corners_flz: np.ndarray, kind: str) -> None:
        self.corners.append(np.asarray(corners_flz, dtype=np.float64))
        self.kinds.append(kind)

    def place(self, x_m: float, y_m: float, heading_rad: float) -> Shape:
        local = np.stack(self.corners)
        c, s = math.cos(heading_rad), math.sin(heading_rad)
        world = np.empty_like(local)
        world[..., 0] = x_m + c * local[..., 0] - s * local[..., 1]
        world[..., 1] = y_m + s * local[..., 0] + c * local[..., 1]
        world[..., 2] = local[..., 2]
        refl = np.array([IR_REFLECTANCE[k] for k in self.kinds])
        return Shape(world, refl, tuple(self.kinds))


def box(f0: float, f1: float, l0: float, l1: float, z0: float, z1: float) -> np.ndarray:
    """Axis-aligned box in the local frame, 8 corners."""
    return np.array([[f, lat, z] for z in (z0, z1) for lat in (l0, l1) for f in (f0, f1)])


def slab(
    bottom_flz: Sequence[float], top_flz: Sequence[float], half_f_m: float, half_l_m: float
) -> np.ndarray:
    """Sheared box: horizontal 2*half_f x 2*half_l faces centred at the two ends (a limb), 8 corners."""
    out = []
    for cf, cl, cz in (bottom_flz, top_flz):
        for dl in (-half_l_m, half_l_m):
            for df in (-half_f_m, half_f_m):
                out.append([cf + df, cl + dl, cz])
    return np.array(out)


def octagon(f_m: float, l_m: float, z_m: float, radius_m: float) -> np.ndarray:
    """Flat octagon (a wheel) in the forward-up plane; vertices at 0, 45, ... deg so its
    forward and vertical extents are exactly 2 * radius."""
    ang = np.arange(8) * (math.pi / 4)
    return np.column_stack(
        [f_m + radius_m * np.cos(ang), np.full(8, l_m), z_m + radius_m * np.sin(ang)]
    )


def trapezoid_prism(
    f_bottom: tuple[float, float],
    f_top: tuple[float, float],
    half_l_bottom: float,
    half_l_top: float,
    z0: float,
    z1: float,
) -> np.ndarray:
    """Prism narrowing upwards (a car cabin): a convex solid, 8 corners."""
    out = []
    for (fa, fb), hl, z in ((f_bottom, half_l_bottom, z0), (f_top, half_l_top, z1)):
        for lat in (-hl, hl):
            for f in (fa, fb):
                out.append([f, lat, z])
    return np.array(out)
