"""The compiled pixel tests of division (``detector.split_compiled``) equal ``detector.split``'s."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from detector import split, split_compiled
from detector.split import DivisionParams


def filled_region(rng: np.random.Generator) -> np.ndarray:
    """The filled mask (0/1 uint8, its own bounding box) of a random upright body and, mostly, a
    flat spot beside it, in front of it, behind it or under it, or of a blob on a widening beam."""
    h, w = 120, 160
    mask = np.zeros((h, w), np.uint8)
    cx, cy = int(rng.integers(50, 110)), int(rng.integers(30, 70))
    half_w, half_h = int(rng.integers(3, 15)), int(rng.integers(6, 30))
    cv2.ellipse(mask, (cx, cy), (half_w, half_h), 0, 0, 360, 1, -1)
    kind = rng.integers(0, 4)
    if kind == 1:  # a flat spot: its centre row anywhere from above the feet to well below them
        spot_cx = cx + int(rng.integers(-40, 41))
        spot_cy = cy + half_h + int(rng.integers(-12, 20))
        axes = (int(rng.integers(6, 45)), int(rng.integers(2, 10)))
        cv2.ellipse(mask, (spot_cx, spot_cy), axes, 0, 0, 360, 1, -1)
    elif kind == 2:  # a beam flaring out under the blob
        base = cy + half_h - 2
        flare = base + int(rng.integers(4, 16))
        bottom = min(h - 1, flare + int(rng.integers(5, 40)))
        spread = int(rng.integers(10, 60))
        beam = np.array([[cx - 3, base], [cx + 3, base], [cx + half_w + spread // 3, flare],
                         [cx + spread, bottom], [cx - spread, bottom], [cx - half_w - spread // 3, flare]],
                        np.int32)  # fmt: skip
        cv2.fillPoly(mask, [beam], 1)
    elif kind == 3:  # blobs of noise joined to the body
        for _ in range(int(rng.integers(1, 6))):
            x, y = cx + int(rng.integers(-30, 31)), cy + int(rng.integers(-30, 45))
            cv2.circle(mask, (x, y), int(rng.integers(1, 9)), 1, -1)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    biggest = max(contours, key=cv2.contourArea)
    x, y, bw, bh = cv2.boundingRect(biggest)
    roi = np.zeros((bh, bw), np.uint8)
    cv2.drawContours(roi, [biggest], 0, 1, thickness=cv2.FILLED, offset=(-x, -y))
    return roi


@pytest.mark.parametrize("params", [DivisionParams(), DivisionParams(max_spot_aspect=2.0, tall_fraction=0.3)])
def test_compiled_splits_equal_the_reference(params):
    rng = np.random.default_rng(3)
    splits = {"split_object_and_spot": 0, "split_at_widening": 0}
    for _ in range(3000):
        roi = filled_region(rng)
        for name in splits:
            want = getattr(split, name)(roi.view(bool), params)
            got = getattr(split_compiled, name)(roi, params)
            assert (got is None) == (want is None), name
            if want is not None:
                splits[name] += 1
                for part_got, part_want in zip(got, want, strict=True):
                    assert part_got.dtype == bool and np.array_equal(part_got, part_want), name
    assert min(splits.values()) > 100, splits  # both tests split many of the masks, and refused many


def test_compiled_splits_refuse_small_and_empty_masks():
    for shape in ((5, 40), (40, 5), (7, 7)):
        roi = np.zeros(shape, np.uint8)
        assert split_compiled.split_object_and_spot(roi) is None
        assert split_compiled.split_at_widening(roi) is None
    assert split_compiled.split_at_widening(np.ones((40, 20), np.uint8)) is None


def test_a_parts_box_is_the_union_of_its_external_contours_boxes():
    # divide._part_box_and_area takes the mask's own box: the union of its contours' boxes
    from detector.divide import _part_box_and_area

    rng = np.random.default_rng(8)
    n_parts = 0
    for _ in range(1500):
        parts = split.split_object_and_spot(filled_region(rng).view(bool)) or ()
        for part in parts:
            contours, _ = cv2.findContours(part.view(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
            rects = np.array([cv2.boundingRect(c) for c in contours])
            left, top = rects[:, :2].min(axis=0)
            right, bottom = (rects[:, :2] + rects[:, 2:]).max(axis=0)
            box, area = _part_box_and_area(part, 3, 5)
            assert box == [3 + left, 5 + top, right - left, bottom - top]
            assert area == sum(cv2.contourArea(c) for c in contours)
            n_parts += 1
    assert n_parts > 500
