"""The 3D models have the Table 1 extents they are asked for, stand on the ground,
move their limbs with the gait, and rasterise where the camera says they are."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

import detector.classes as classes
from detector.train.shapes import (
    animal_shape,
    cyclist_shape,
    group_shape,
    pedestrian_shape,
    silhouette_mask,
    vehicle_shape,
)
from tests.detector.cameras import scene_b

SCENE_B = scene_b()

# (width, height, length) corners of the Table 1 boxes of the classes built as one model
TABLE1 = {
    cls: (size.width_m, size.height_m, size.length_m)
    for cls, size in classes.TABLE1.items()
    if cls in ("pedestrian", "cyclist", "vehicle")
}


def _build(
    cls: str, x: float, y: float, heading: float, w: float, h: float, length: float, phase: float
):
    if cls == "pedestrian":
        return pedestrian_shape(x, y, heading, w, h, length, phase)
    if cls == "cyclist":
        return cyclist_shape(x, y, heading, w, h, length, phase)
    return vehicle_shape(x, y, heading, w, h, length)


@pytest.mark.parametrize("cls", sorted(TABLE1))
@pytest.mark.parametrize("corner", range(8))
def test_extents_match_requested_sizes(cls: str, corner: int) -> None:
    (w0, w1), (h0, h1), (l0, l1) = TABLE1[cls]
    w = (w0, w1)[corner & 1]
    h = (h0, h1)[(corner >> 1) & 1]
    length = (l0, l1)[(corner >> 2) & 1]
    heading = 0.3 + corner  # any direction
    shape = _build(cls, 12.0, -4.0, heading, w, h, length, math.pi / 2)
    got_l, got_w, got_h = shape.extents_m(heading)
    assert got_w == pytest.approx(w, abs=1e-9)
    assert got_h == pytest.approx(h, abs=1e-9)
    assert got_l == pytest.approx(length, abs=1e-9)
    assert shape.corners_m[..., 2].min() == pytest.approx(0.0, abs=1e-9), "must stand on the ground"
    footprint = shape.corners_m[..., :2].reshape(-1, 2)
    centre = (footprint.min(axis=0) + footprint.max(axis=0)) / 2
    assert np.hypot(*(centre - [12.0, -4.0])) < 0.6 * length


def test_pedestrian_stride_follows_gait_phase() -> None:
    lengths = [
        pedestrian_shape(0, 0, 0.0, 0.5, 1.7, 0.7, p).extents_m(0.0)[0]
        for p in np.linspace(0, math.pi, 9)
    ]
    assert lengths[0] < 0.3 and lengths[4] == pytest.approx(0.7)
    assert np.all(np.diff(lengths[:5]) > 0) and np.all(np.diff(lengths[4:]) < 0)
    # the two legs move in opposite directions
    legs = [
        i
        for i, k in enumerate(pedestrian_shape(0, 0, 0.0, 0.5, 1.7, 0.7, 1.0).part_kind)
        if k == "leg"
    ]
    shape = pedestrian_shape(0, 0, 0.0, 0.5, 1.7, 0.7, 1.0)
    feet_x = [shape.corners_m[i, :4, 0].mean() for i in legs]
    assert feet_x[0] == pytest.approx(-feet_x[1]) and abs(feet_x[0]) > 0.1


def test_cyclist_legs_follow_crank_and_stay_inside_bicycle() -> None:
    a = cyclist_shape(0, 0, 0.0, 0.5, 1.7, 1.6, 0.0)
    b = cyclist_shape(0, 0, 0.0, 0.5, 1.7, 1.6, math.pi / 2)
    legs = [i for i, k in enumerate(a.part_kind) if k == "leg"]
    assert not np.allclose(a.corners_m[legs], b.corners_m[legs])
    assert set(a.part_kind) >= {"wheel", "frame", "handlebar", "torso", "head", "arm", "leg"}
    for phase in np.linspace(0, 2 * math.pi, 7):
        assert cyclist_shape(0, 0, 0.0, 0.5, 1.7, 1.6, phase).extents_m(0.0) == pytest.approx(
            (1.6, 0.5, 1.7)
        )


def test_group_spans_its_members() -> None:
    members = [
        (0.0, -1.0, 0.5, 1.8, 0.6, 0.0),
        (0.1, 0.0, 0.4, 1.6, 0.6, 1.0),
        (0.0, 1.0, 0.5, 1.7, 0.6, 2.0),
    ]
    shape = group_shape(3.0, 1.0, math.pi / 3, members)
    length, width, height = shape.extents_m(math.pi / 3)
    assert width == pytest.approx(2.5) and height == pytest.approx(1.8)
    assert shape.n_parts == 3 * 6 and shape.part_kind.count("head") == 3
    with pytest.raises(ValueError, match="at least one member"):
        group_shape(0, 0, 0, [])


def test_animal_is_small_quadruped() -> None:
    shape = animal_shape(0, 0, 1.0, 0.25, 0.6, 0.9, 0.5)
    assert shape.extents_m(1.0) == pytest.approx((0.9, 0.25, 0.6))
    assert shape.part_kind.count("leg") == 4


def test_silhouette_lands_where_the_camera_projects_it() -> None:
    shape = pedestrian_shape(8.0, 0.5, 1.0, 0.5, 1.75, 0.6, 0.8)
    sil = silhouette_mask(SCENE_B, shape)
    assert sil is not None and not sil.touches_border
    x, y, w, h = cv2.boundingRect(sil.mask)
    x += sil.offset_px[0]
    y += sil.offset_px[1]
    uv = SCENE_B.project(shape.corners_m.reshape(-1, 3))
    assert abs(x - uv[:, 0].min()) <= 1.0 and abs(x + w - 1 - uv[:, 0].max()) <= 1.0
    assert abs(y - uv[:, 1].min()) <= 1.0 and abs(y + h - 1 - uv[:, 1].max()) <= 1.0
    # a far-away object is smaller; one behind the camera is not drawn; one at the edge touches it
    far = silhouette_mask(SCENE_B, pedestrian_shape(20.0, 0.5, 1.0, 0.5, 1.75, 0.6, 0.8))
    assert far is not None and far.mask.sum() < sil.mask.sum() / 4
    assert silhouette_mask(SCENE_B, pedestrian_shape(-5.0, 0.0, 1.0, 0.5, 1.75, 0.6, 0.8)) is None
    edge = silhouette_mask(SCENE_B, vehicle_shape(5.0, 4.0, 0.0, 1.7, 1.5, 4.2))
    assert edge is not None and edge.touches_border


def test_parts_and_silhouettes_stay_importable_from_shapes() -> None:
    import detector.train.shape_parts as shape_parts
    import detector.train.shapes as shapes
    import detector.train.silhouette as silhouette

    for name in ("Shape", "IR_REFLECTANCE", "VERTICES_PER_PART", "Parts"):
        assert getattr(shapes, name) is getattr(shape_parts, name)
    for name in (
        "Silhouette",
        "SUBPIXEL_BITS",
        "project_parts",
        "rasterise_parts",
        "silhouette_mask",
    ):
        assert getattr(shapes, name) is getattr(silhouette, name)
    walker = shapes.pedestrian_shape(10.0, 0.0, 0.0, 0.5, 1.75, 0.7, 1.0)
    assert isinstance(walker, shapes.Shape) and walker.n_parts == 6
    assert walker.corners_m.shape[1] == shapes.VERTICES_PER_PART
