"""Articulated 3D models of the paper's object classes, built from convex parts.

The classifier's synthetic training data (``detector.train.sets``) and the
simulator's renderer project the *same* models, so what the detector learns is
what the simulated camera shows.

Conventions:

* World frame of docs/design/architecture.md: x along the street, y across it, z up, metres;
  the ground is z = 0 and every model stands on it.
* ``x_m, y_m`` is the centre of the model's ground footprint; ``heading_rad``
  is its direction of motion, counter-clockwise from +x.
* Sizes follow the paper's Table 1 (``detector.classes.TABLE1``): ``width_m``
  across the heading, ``height_m`` up, ``length_m`` along the heading ("depth":
  step length for walkers, bicycle length for cyclists, car length for
  vehicles). A built
  model's axis-aligned extents in its own frame equal these numbers (for a
  walker, the length is reached at full stride, ``gait_phase_rad = pi/2``).
* Every part is a convex solid given by K = 8 vertices (a box, a sheared box
  or a flat octagon for wheels; ``detector.train.shape_parts``); the
  silhouette of a model is the union of the convex hulls of its projected
  parts (``detector.train.silhouette``).

Builders are pure functions: no randomness inside; callers draw the sizes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

# the parts and the silhouettes of these models live in their own modules; every name
# stays importable from here
from detector.train.shape_parts import (
    IR_REFLECTANCE,
    VERTICES_PER_PART,
    Parts,
    Shape,
    box,
    octagon,
    slab,
    trapezoid_prism,
)
from detector.train.silhouette import (
    SUBPIXEL_BITS,
    Silhouette,
    project_parts,
    rasterise_parts,
    silhouette_mask,
)

__all__ = [
    "IR_REFLECTANCE",
    "SUBPIXEL_BITS",
    "VERTICES_PER_PART",
    "Parts",
    "Shape",
    "Silhouette",
    "animal_shape",
    "blob_shape",
    "box",
    "cyclist_shape",
    "ground_spot_shape",
    "group_shape",
    "octagon",
    "pedestrian_shape",
    "project_parts",
    "rasterise_parts",
    "silhouette_mask",
    "slab",
    "trapezoid_prism",
    "vehicle_shape",
]


# ------------------------------------------------------------------- builders
def _walker_parts(
    parts: Parts,
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
        box(f0 - head_d / 2, f0 + head_d / 2, l0 - head_w / 2, l0 + head_w / 2, z_neck, h), "head"
    )
    torso_w = 0.64 * w
    parts.add(
        box(
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
        parts.add(slab(hand, shoulder, 0.4 * leg_depth, arm_w / 2), "arm")

    leg_w = 0.28 * w
    leg_l = 0.32 * w - leg_w / 2
    for side in (-1.0, 1.0):
        hip = (f0, l0 + side * leg_l, z_hip + 0.02 * h)
        foot = (f0 + side * swing, l0 + side * leg_l, 0.0)
        parts.add(slab(foot, hip, leg_depth / 2, leg_w / 2), "leg")


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
    parts = Parts()
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
    parts = Parts()
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
    parts = Parts()
    wheel_d = min(max(0.4 * length, 0.5), 0.7)
    r = wheel_d / 2
    f_rear, f_front = -length / 2 + r, length / 2 - r
    wheelbase = f_front - f_rear
    parts.add(octagon(f_rear, 0.0, r, r), "wheel")
    parts.add(octagon(f_front, 0.0, r, r), "wheel")

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
        box(f_bar - 0.03, f_bar + 0.03, -w / 2, w / 2, z_bar - 0.03, z_bar + 0.03), "handlebar"
    )

    # rider leans forward: shoulders between saddle and handlebar
    z_shoulder, z_neck = 0.85 * h, 0.87 * h
    f_shoulder = f_seat + 0.55 * (f_bar - f_seat)
    shoulder_w = 0.8 * w
    torso_d = min(0.36 * w, 0.22)
    hip = (f_seat, 0.0, z_saddle + 0.03)
    parts.add(slab(hip, (f_shoulder, 0.0, z_neck), torso_d / 2, 0.32 * w), "torso")
    head_w = min(0.32 * w, 0.2)
    parts.add(box(f_shoulder, f_shoulder + 0.2, -head_w / 2, head_w / 2, z_neck, h), "head")
    for side in (-1.0, 1.0):
        lat = side * (shoulder_w / 2 - 0.05)
        parts.add(
            slab((f_bar, side * (w / 2 - 0.06), z_bar), (f_shoulder, lat, z_shoulder), 0.04, 0.04),
            "arm",
        )

    crank_m = 0.17
    f_bb, z_bb = f_rear + 0.42 * wheelbase, 0.45 * r + 0.12
    for side in (-1.0, 1.0):
        pedal_f = f_bb + side * crank_m * math.cos(crank_phase_rad)
        pedal_z = max(z_bb + side * crank_m * math.sin(crank_phase_rad), 0.06)
        lat = side * 0.12 * w
        parts.add(slab((pedal_f, lat, pedal_z - 0.05), (hip[0], lat, hip[2]), 0.06, 0.07), "leg")
    return parts.place(x_m, y_m, heading_rad)


def vehicle_shape(
    x_m: float, y_m: float, heading_rad: float, width_m: float, height_m: float, length_m: float
) -> Shape:
    """A car: body, cabin and four wheels (6 parts); extents = length x width x height."""
    w, h, length = width_m, height_m, length_m
    parts = Parts()
    z_body_top = 0.55 * h
    r = min(0.31, 0.5 * z_body_top)
    parts.add(box(-length / 2, length / 2, -w / 2, w / 2, 0.6 * r, z_body_top), "body")
    parts.add(
        trapezoid_prism(
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
            parts.add(octagon(f, side * (w / 2 - 0.02), r, r), "wheel")
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
    parts = Parts()
    z_belly, z_back = 0.45 * h, 0.75 * h
    f_back, f_chest = -0.32 * length, 0.25 * length
    parts.add(box(f_back, f_chest, -w / 2, w / 2, z_belly, z_back), "torso")
    head_w = 0.7 * w
    parts.add(
        box(f_chest - 0.05 * length, length / 2, -head_w / 2, head_w / 2, 0.62 * h, h), "head"
    )
    parts.add(box(-length / 2, f_back + 0.02, -0.15 * w, 0.15 * w, 0.55 * h, 0.65 * h), "tail")
    swing = 0.12 * length * math.sin(gait_phase_rad)
    leg_half = 0.12 * w
    for f_hip, sign in ((f_back + 0.06 * length, 1.0), (f_chest - 0.06 * length, -1.0)):
        for side in (-1.0, 1.0):
            lat = side * (w / 2 - leg_half)
            foot = (f_hip + sign * side * swing, lat, 0.0)
            parts.add(slab(foot, (f_hip, lat, z_belly + 0.05 * h), 0.04 * length, leg_half), "leg")
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
    parts = Parts()
    parts.add(
        box(-length_m / 2, length_m / 2, -width_m / 2, width_m / 2, z0_m, z0_m + height_m), "body"
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
    parts = Parts()
    parts.add(corners, "spot")
    return parts.place(x_m, y_m, heading_rad)
