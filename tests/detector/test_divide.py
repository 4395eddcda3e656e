"""Division of a compact blob standing on a much wider flat light spot (a car on its headlight beam)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from detector.camera import CameraModel
from detector.contours import contour_boxes_and_areas
from detector.detector import Detector
from detector.divide import DivisionParams, divide_regions
from detector.features import region_features
from detector.split import split_at_widening
from tests.detector.cameras import scene_b

H_PX, W_PX = 240, 320
BLOB_BOX = (150, 60, 24, 18)  # x, y, w, h: a car ~25 m away, head-on


def region(mask: np.ndarray, camera: CameraModel):
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    assert len(contours) == 1, "blob and beam must form one region"
    boxes, areas = contour_boxes_and_areas(contours)
    feats, valid = region_features(camera, boxes, areas)
    return list(contours), boxes, areas, feats, valid


def car_on_beam(bottom_px: int, right_px: int) -> np.ndarray:
    """A rounded blob whose base flares within a dozen rows into a wide beam reaching down to bottom_px."""
    mask = np.zeros((H_PX, W_PX), np.uint8)
    x, y, w, h = BLOB_BOX
    cv2.ellipse(mask, (x + w // 2, y + h // 2), (w // 2, h // 2), 0, 0, 360, 255, -1)
    mask[y + 3 : y + h - 3, x : x + w] = 255
    base = y + h - 2
    flare = base + 12
    beam = np.array(
        [
            [x + 4, base],
            [x + w - 4, base],
            [x + w + 30, flare],
            [right_px, bottom_px],
            [x - 90, bottom_px],
            [x - 30, flare],
        ],
        np.int32,
    )
    cv2.fillPoly(mask, [beam], 255)
    return mask


def blob_mask() -> np.ndarray:
    """The car alone: ``car_on_beam``'s blob without its beam."""
    mask = np.zeros((H_PX, W_PX), np.uint8)
    x, y, w, h = BLOB_BOX
    cv2.ellipse(mask, (x + w // 2, y + h // 2), (w // 2, h // 2), 0, 0, 360, 255, -1)
    mask[y + 3 : y + h - 3, x : x + w] = 255
    return mask


def iou(a, b) -> float:
    ax, ay, aw, ah = a
    bx, by, bw, bh = b
    iw = max(0, min(ax + aw, bx + bw) - max(ax, bx))
    ih = max(0, min(ay + ah, by + bh) - max(ay, by))
    return iw * ih / (aw * ah + bw * bh - iw * ih)


@pytest.mark.parametrize("bottom_px, right_px", [(170, 290), (H_PX - 1, 300), (200, W_PX - 1)])
def test_blob_on_a_wide_beam_is_cut_at_its_base(bottom_px, right_px):
    cam = scene_b()
    mask = car_on_beam(bottom_px, right_px)
    contours, boxes, areas, feats, valid = region(mask, cam)
    out = divide_regions(cam, contours, boxes, areas, feats, valid)
    assert out.divided.tolist() == [True]
    assert iou(out.boxes_px[0], BLOB_BOX) >= 0.8
    # the object part is nearer its true distance than the merged region's bottom says
    assert out.features[0, 3] > feats[0, 3] + 5.0
    sx, sy, sw, sh = out.spot_boxes_px[0]
    assert sy >= BLOB_BOX[1] + BLOB_BOX[3] - 6 and sw > 3 * BLOB_BOX[2]


def test_lone_blobs_stay_whole():
    cam = scene_b()
    # a pedestrian: head, wider torso, legs apart; and a side-view car: cabin on a longer body
    walker = np.zeros((H_PX, W_PX), np.uint8)
    cv2.ellipse(walker, (100, 70), (4, 5), 0, 0, 360, 255, -1)
    walker[75:110, 93:108] = 255
    cv2.fillPoly(walker, [np.array([[94, 110], [106, 110], [112, 140], [88, 140]], np.int32)], 255)
    car = np.zeros((H_PX, W_PX), np.uint8)
    cv2.fillPoly(car, [np.array([[130, 90], [175, 90], [190, 105], [120, 105]], np.int32)], 255)
    car[105:125, 100:215] = 255
    for mask in (walker, car):
        contours, boxes, areas, feats, valid = region(mask, cam)
        out = divide_regions(
            cam, contours, boxes, areas, feats, valid, DivisionParams(max_extent=1)
        )
        assert out.divided.tolist() == [False]
        np.testing.assert_array_equal(out.boxes_px, boxes)


def test_split_at_widening_needs_the_lower_part_to_stay_wide():
    # an arm at mid height widens a few rows, then the narrow body goes on: no spot
    arm = np.zeros((60, 40), bool)
    arm[:, 10:22] = True
    arm[20:26, 22:40] = True
    assert split_at_widening(arm) is None
    assert split_at_widening(np.ones((40, 20), bool)) is None


def test_detector_classifies_the_object_cut_off_a_border_region():
    cam = scene_b()
    det = Detector(cam)
    rng = np.random.default_rng(0)
    background = rng.normal(40, 2, (H_PX, W_PX))
    for _ in range(60):
        assert det.process(np.clip(background, 0, 255).astype(np.uint8)) == []
    found = []
    for _ in range(3):
        img = background + rng.normal(0, 2, (H_PX, W_PX))
        img[car_on_beam(H_PX - 1, W_PX - 1) > 0] = 200  # the beam lights the road
        img[blob_mask() > 0] = 110  # the car's body, darker than the lit road
        found = det.process(np.clip(img, 0, 255).astype(np.uint8))
    regions = det.last_regions
    assert len(regions) == 1 and regions.touches_border.all()
    # the segmenter's joining dilation grows the blob by a few pixels on each side
    assert len(found) == 1
    x, y, w, h = BLOB_BOX
    grown = (x - 3, y - 3, w + 6, h + 6)
    assert iou(found[0].box_px, grown) >= 0.7 and iou(found[0].box_px, BLOB_BOX) >= 0.6


def test_beam_params_are_validated():
    with pytest.raises(ValueError, match="widen_ratio"):
        DivisionParams(widen_ratio=1.0)
    with pytest.raises(ValueError, match="min_top_rows"):
        DivisionParams(min_top_rows=1)
    with pytest.raises(ValueError, match="max_beam_height_to_width"):
        DivisionParams(max_beam_height_to_width=0.0)


def _detect_shape(ground_dn: int, body_dn: int, beam_dn: int) -> list:
    """The Detector's detections in a frame where the car-on-beam shape (``car_on_beam(170, 290)``)
    is drawn on a plain ground after 30 frames of the empty ground: the blob in ``body_dn``,
    the rest of the shape in ``beam_dn``."""
    detector = Detector(scene_b(), crop_to_range=False)
    rng = np.random.default_rng(0)
    ground = np.full((H_PX, W_PX), ground_dn, np.uint8)
    for _ in range(30):
        detector.process(np.clip(ground + rng.normal(0, 2, ground.shape), 0, 255).astype(np.uint8))
    frame = ground.copy()
    frame[car_on_beam(170, 290) > 0] = beam_dn
    frame[blob_mask() > 0] = body_dn
    return detector.process(np.clip(frame + rng.normal(0, 2, frame.shape), 0, 255).astype(np.uint8))


def test_division_only_where_the_spot_is_light():
    """Night: a headlight beam brightens the ground, the car is cut off it. Day: the same shape in
    one bright paint (a car's roof above its wider body, brighter than the road) is not divided:
    no light spot there."""
    night = _detect_shape(ground_dn=30, body_dn=90, beam_dn=170)
    assert any(iou(d.box_px, BLOB_BOX) >= 0.7 for d in night), [d.box_px for d in night]  # grown by the dilation
    day = _detect_shape(ground_dn=90, body_dn=200, beam_dn=200)
    assert day and not any(iou(d.box_px, BLOB_BOX) >= 0.5 for d in day), [d.box_px for d in day]
