"""Articulated 3D models of the paper's object classes, built from convex parts.

The classifier's synthetic training data (``detector.training``) and the
simulator's renderer project the *same* models, so what the detector learns is
what the simulated camera shows.

Conventions:

* World frame of DESIGN.md: x along the street, y across it, z up, metres;
  the ground is z = 0 and every model stands on it.
* ``x_m, y_m`` is the centre of the model's ground footprint; ``heading_rad``
  is its direction of motion, counter-clockwise from +x.
* Sizes follow the paper's Table 1: ``width_m`` across the heading,
  ``height_m`` up, ``length_m`` along the heading ("depth": step length for
  walkers, bicycle length for cyclists, car length for vehicles). A built
  model's axis-aligned extents in its own frame equal these numbers (for a
  walker, the length is reached at full stride, ``gait_phase_rad = pi/2``).
* Every part is a convex solid given by K = 8 vertices (a box, a sheared box
  or a flat octagon for wheels); the silhouette of a model is the union of the
  convex hulls of its projected parts.

Builders are pure functions: no randomness inside; callers draw the sizes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from detector.camera import CameraModel

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

    def translated(self, dx_m: float, dy_m: float) -> Shape:
        """The same model moved on the ground by (dx, dy), m."""
        return Shape(
            self.corners_m + np.array([dx_m, dy_m, 0.0]), self.ir_reflectance, self.part_kind
        )


# ----------------------------------------------------------------- part helpers
# Parts are first built in the model's local frame (forward f, left l, up z),
# then placed; ``_Parts`` collects them in order.


class _Parts:
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


def _box(f0: float, f1: float, l0: float, l1: float, z0: float, z1: float) -> np.ndarray:
    """Axis-aligned box in the local frame, 8 corners."""
    return np.array([[f, lat, z] for z in (z0, z1) for lat in (l0, l1) for f in (f0, f1)])


def _slab(
    bottom_flz: Sequence[float], top_flz: Sequence[float], half_f_m: float, half_l_m: float
) -> np.ndarray:
    """Sheared box: horizontal 2*half_f x 2*half_l faces centred at the two ends (a limb), 8 corners."""
    out = []
    for cf, cl, cz in (bottom_flz, top_flz):
        for dl in (-half_l_m, half_l_m):
            for df in (-half_f_m, half_f_m):
                out.append([cf + df, cl + dl, cz])
    return np.array(out)


def _octagon(f_m: float, l_m: float, z_m: float, radius_m: float) -> np.ndarray:
    """Flat octagon (a wheel) in the forward-up plane; vertices at 0, 45, ... deg so its
    forward and vertical extents are exactly 2 * radius."""
    ang = np.arange(8) * (math.pi / 4)
    return np.column_stack(
        [f_m + radius_m * np.cos(ang), np.full(8, l_m), z_m + radius_m * np.sin(ang)]
    )


def _trapezoid_prism(
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


# ------------------------------------------------------------------- builders
def _walker_parts(
    parts: _Parts,
    f0: float,
    l0: float,
    width_m: float,
    height_m: float,
    step_m: float,
    gait_phase_rad: float,
) -> None:
    """One pedestrian in the local frame, centred at (f0, l0).

    Proportions are fractions of height (hips at 0.48 H, shoulders at 0.85 H,
    head 0.13 H) and of width (arms reach the full width). Legs are sheared
    boxes from hip to foot, so both feet stay on the ground; the feet are
    +-f_max * sin(phase) from the hip, which makes the stride, outer toe to
    outer heel, exactly ``step_m`` at phase pi/2.
    """
    w, h = width_m, height_m
    torso_depth = min(0.45 * w, step_m)
    leg_depth = 0.7 * torso_depth
    f_max = max(0.0, (step_m - leg_depth) / 2.0)
    swing = f_max * math.sin(gait_phase_rad)
    z_hip, z_shoulder, z_neck = 0.48 * h, 0.85 * h, 0.87 * h

    head_w = min(0.32 * w, 0.2)
    head_d = min(0.2, torso_depth)
    parts.add(
        _box(f0 - head_d / 2, f0 + head_d / 2, l0 - head_w / 2, l0 + head_w / 2, z_neck, h), "head"
    )
    torso_w = 0.64 * w
    parts.add(
        _box(
            f0 - torso_depth / 2,
            f0 + torso_depth / 2,
            l0 - torso_w / 2,
            l0 + torso_w / 2,
            z_hip,
            z_neck,
        ),
        "torso",
    )

    arm_w = 0.18 * w
    arm_l = w / 2 - arm_w / 2
    arm_swing = 0.5 * swing  # arms swing less than legs and opposite to the leg on their side
    for side in (-1.0, 1.0):
        shoulder = (f0, l0 + side * arm_l, z_shoulder)
        hand = (f0 - side * arm_swing, l0 + side * arm_l, z_hip)
        parts.add(_slab(hand, shoulder, 0.4 * leg_depth, arm_w / 2), "arm")

    leg_w = 0.28 * w
    leg_l = 0.32 * w - leg_w / 2
    for side in (-1.0, 1.0):
        hip = (f0, l0 + side * leg_l, z_hip + 0.02 * h)
        foot = (f0 + side * swing, l0 + side * leg_l, 0.0)
        parts.add(_slab(foot, hip, leg_depth / 2, leg_w / 2), "leg")


def pedestrian_shape(
    x_m: float,
    y_m: float,
    heading_rad: float,
    width_m: float,
    height_m: float,
    step_m: float,
    gait_phase_rad: float,
) -> Shape:
    """A walking pedestrian: head, torso, two arms, two legs (6 parts).

    Width across the shoulders/arms = ``width_m``; height = ``height_m``;
    length along the heading = max(torso depth, stride) where the stride is
    ``step_m * |sin(gait_phase_rad)|`` plus the leg depth (``step_m`` at full stride).
    """
    parts = _Parts()
    _walker_parts(parts, 0.0, 0.0, width_m, height_m, step_m, gait_phase_rad)
    return parts.place(x_m, y_m, heading_rad)


def group_shape(
    x_m: float,
    y_m: float,
    heading_rad: float,
    members: Sequence[tuple[float, float, float, float, float, float]],
) -> Shape:
    """Pedestrians walking together: ``members`` are (forward_m, left_m, width_m,
    height_m, step_m, gait_phase_rad), offsets relative to (x_m, y_m) along and
    to the left of the common heading."""
    if len(members) == 0:
        raise ValueError("group_shape needs at least one member, got 0")
    parts = _Parts()
    for fwd, left, w, h, step, phase in members:
        _walker_parts(parts, fwd, left, w, h, step, phase)
    return parts.place(x_m, y_m, heading_rad)


def cyclist_shape(
    x_m: float,
    y_m: float,
    heading_rad: float,
    width_m: float,
    height_m: float,
    length_m: float,
    crank_phase_rad: float,
) -> Shape:
    """A rider on a bicycle: two wheels, frame, handlebar, torso, head, two arms, two legs (10 parts).

    Bicycle length (rear tyre to front tyre) = ``length_m``; handlebar width =
    ``width_m``; the top of the rider's head = ``height_m``. The legs follow the
    pedals, which turn with ``crank_phase_rad``.
    """
    w, h, length = width_m, height_m, length_m
    parts = _Parts()
    wheel_d = min(max(0.4 * length, 0.5), 0.7)
    r = wheel_d / 2
    f_rear, f_front = -length / 2 + r, length / 2 - r
    wheelbase = f_front - f_rear
    parts.add(_octagon(f_rear, 0.0, r, r), "wheel")
    parts.add(_octagon(f_front, 0.0, r, r), "wheel")

    z_saddle = 0.5 * h
    z_bar = z_saddle + 0.08 * h
    f_seat = f_rear + 0.28 * wheelbase
    f_head_tube = f_front - 0.12 * wheelbase
    frame = []
    for dl in (-0.03, 0.03):
        frame += [
            [f_rear, dl, r],
            [f_front, dl, r],
            [f_head_tube, dl, z_bar],
            [f_seat, dl, z_saddle],
        ]
    parts.add(np.array(frame), "frame")
    f_bar = f_head_tube - 0.05
    parts.add(
        _box(f_bar - 0.03, f_bar + 0.03, -w / 2, w / 2, z_bar - 0.03, z_bar + 0.03), "handlebar"
    )

    # rider leans forward: shoulders between saddle and handlebar
    z_shoulder, z_neck = 0.85 * h, 0.87 * h
    f_shoulder = f_seat + 0.55 * (f_bar - f_seat)
    shoulder_w = 0.8 * w
    torso_d = min(0.36 * w, 0.22)
    hip = (f_seat, 0.0, z_saddle + 0.03)
    parts.add(_slab(hip, (f_shoulder, 0.0, z_neck), torso_d / 2, 0.32 * w), "torso")
    head_w = min(0.32 * w, 0.2)
    parts.add(_box(f_shoulder, f_shoulder + 0.2, -head_w / 2, head_w / 2, z_neck, h), "head")
    for side in (-1.0, 1.0):
        lat = side * (shoulder_w / 2 - 0.05)
        parts.add(
            _slab((f_bar, side * (w / 2 - 0.06), z_bar), (f_shoulder, lat, z_shoulder), 0.04, 0.04),
            "arm",
        )

    crank_m = 0.17
    f_bb, z_bb = f_rear + 0.42 * wheelbase, 0.45 * r + 0.12
    for side in (-1.0, 1.0):
        pedal_f = f_bb + side * crank_m * math.cos(crank_phase_rad)
        pedal_z = max(z_bb + side * crank_m * math.sin(crank_phase_rad), 0.06)
        lat = side * 0.12 * w
        parts.add(_slab((pedal_f, lat, pedal_z - 0.05), (hip[0], lat, hip[2]), 0.06, 0.07), "leg")
    return parts.place(x_m, y_m, heading_rad)


def vehicle_shape(
    x_m: float, y_m: float, heading_rad: float, width_m: float, height_m: float, length_m: float
) -> Shape:
    """A car: body, cabin and four wheels (6 parts); extents = length x width x height."""
    w, h, length = width_m, height_m, length_m
    parts = _Parts()
    z_body_top = 0.55 * h
    r = min(0.31, 0.5 * z_body_top)
    parts.add(_box(-length / 2, length / 2, -w / 2, w / 2, 0.6 * r, z_body_top), "body")
    parts.add(
        _trapezoid_prism(
            (-0.38 * length, 0.18 * length),
            (-0.3 * length, 0.02 * length),
            0.47 * w,
            0.41 * w,
            z_body_top,
            h,
        ),
        "cabin",
    )
    f_axle = length / 2 - max(0.18 * length, r + 0.1)
    for f in (-f_axle, f_axle):
        for side in (-1.0, 1.0):
            parts.add(_octagon(f, side * (w / 2 - 0.02), r, r), "wheel")
    return parts.place(x_m, y_m, heading_rad)


def animal_shape(
    x_m: float,
    y_m: float,
    heading_rad: float,
    width_m: float,
    height_m: float,
    length_m: float,
    gait_phase_rad: float,
) -> Shape:
    """A dog/fox-size quadruped: body, head, tail and four swinging legs (7 parts).

    ``length_m`` is nose to tail tip, ``height_m`` the top of the head, ``width_m`` the body width.
    """
    w, h, length = width_m, height_m, length_m
    parts = _Parts()
    z_belly, z_back = 0.45 * h, 0.75 * h
    f_back, f_chest = -0.32 * length, 0.25 * length
    parts.add(_box(f_back, f_chest, -w / 2, w / 2, z_belly, z_back), "torso")
    head_w = 0.7 * w
    parts.add(
        _box(f_chest - 0.05 * length, length / 2, -head_w / 2, head_w / 2, 0.62 * h, h), "head"
    )
    parts.add(_box(-length / 2, f_back + 0.02, -0.15 * w, 0.15 * w, 0.55 * h, 0.65 * h), "tail")
    swing = 0.12 * length * math.sin(gait_phase_rad)
    leg_half = 0.12 * w
    for f_hip, sign in ((f_back + 0.06 * length, 1.0), (f_chest - 0.06 * length, -1.0)):
        for side in (-1.0, 1.0):
            lat = side * (w / 2 - leg_half)
            foot = (f_hip + sign * side * swing, lat, 0.0)
            parts.add(_slab(foot, (f_hip, lat, z_belly + 0.05 * h), 0.04 * length, leg_half), "leg")
    return parts.place(x_m, y_m, heading_rad)


def blob_shape(
    x_m: float,
    y_m: float,
    heading_rad: float,
    width_m: float,
    height_m: float,
    length_m: float,
    z0_m: float = 0.0,
) -> Shape:
    """One box (a generic non-target blob: debris, foliage, an insect), bottom at ``z0_m``."""
    parts = _Parts()
    parts.add(
        _box(-length_m / 2, length_m / 2, -width_m / 2, width_m / 2, z0_m, z0_m + height_m), "body"
    )
    return parts.place(x_m, y_m, heading_rad)


def ground_spot_shape(
    x_m: float, y_m: float, heading_rad: float, width_m: float, length_m: float
) -> Shape:
    """A light spot on the road (headlight, flashlight): a flat octagonal ellipse 1 cm above
    the ground, ``length_m`` along the heading and ``width_m`` across it."""
    ang = np.arange(8) * (math.pi / 4)
    corners = np.column_stack(
        [length_m / 2 * np.cos(ang), width_m / 2 * np.sin(ang), np.full(8, 0.01)]
    )
    parts = _Parts()
    parts.add(corners, "spot")
    return parts.place(x_m, y_m, heading_rad)


# --------------------------------------------------------------- silhouettes
SUBPIXEL_BITS = 4


@dataclass(frozen=True)
class Silhouette:
    """A rasterised model: ``mask`` (h, w) uint8 {0, 255} cropped at ``offset_px`` (x0, y0)
    of the full frame, and whether the model reaches the frame border."""

    mask: np.ndarray
    offset_px: tuple[int, int]
    touches_border: bool


def project_parts(camera: CameraModel, corners_m: np.ndarray, distort: bool = True) -> np.ndarray:
    """(P, K, 3) world vertices -> (P, K, 2) pixels (OpenCV convention, NaN behind the camera)."""
    p, k, _ = corners_m.shape
    return camera.project(corners_m.reshape(-1, 3), distort=distort).reshape(p, k, 2)


def rasterise_parts(
    uv_px: np.ndarray, width_px: int, height_px: int, margin_px: int = 1
) -> Silhouette | None:
    """Fill the convex hull of every part's projected vertices (P, K, 2) on a cropped canvas.

    Parts with a vertex behind the camera are skipped (their projection is not
    the image of a convex solid). Pixel centres lie on integer coordinates, so
    a pixel is set when its centre falls inside a part. Returns None when
    nothing lands in the frame.
    """
    ok = np.all(np.isfinite(uv_px), axis=(1, 2))
    if not np.any(ok):
        return None
    uv = uv_px[ok]
    lo = np.floor(uv.reshape(-1, 2).min(axis=0)).astype(int) - margin_px
    hi = np.ceil(uv.reshape(-1, 2).max(axis=0)).astype(int) + margin_px
    x0, y0 = max(lo[0], 0), max(lo[1], 0)
    x1, y1 = min(hi[0], width_px - 1), min(hi[1], height_px - 1)
    if x1 < x0 or y1 < y0:
        return None
    mask = np.zeros((y1 - y0 + 1, x1 - x0 + 1), np.uint8)
    scale = 1 << SUBPIXEL_BITS
    fixed = np.round((uv - np.array([x0, y0])) * scale).astype(np.int32)
    for part in fixed:
        hull = cv2.convexHull(part)
        cv2.fillConvexPoly(mask, hull, 255, lineType=cv2.LINE_8, shift=SUBPIXEL_BITS)
    if not mask.any():
        return None
    touches = bool(
        (x0 == 0 and mask[:, 0].any())
        or (y0 == 0 and mask[0].any())
        or (x1 == width_px - 1 and mask[:, -1].any())
        or (y1 == height_px - 1 and mask[-1].any())
    )
    return Silhouette(mask, (int(x0), int(y0)), touches)


def silhouette_mask(camera: CameraModel, shape: Shape, distort: bool = True) -> Silhouette | None:
    """The model's silhouette in ``camera``'s frame (cropped), or None if it is out of view."""
    uv = project_parts(camera, shape.corners_m, distort=distort)
    return rasterise_parts(uv, camera.width_px, camera.height_px)
