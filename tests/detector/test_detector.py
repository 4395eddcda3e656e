"""The detector end to end on synthetic clips drawn with the shared 3D shapes."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from sklearn.linear_model import LogisticRegression

from detector.classes import CLASSES
from detector.confirm import Tracker
from detector.detector import Detection, Detector
from detector.divide import MIN_SPOT_BRIGHTENING_DN, divide_regions
from detector.fast_proba import numpy_predict_proba
from detector.features import SCALAR_MAX_REGIONS, region_features
from detector.general_model import default_model
from detector.segment import Segmenter
from detector.train.shapes import (
    cyclist_shape,
    ground_spot_shape,
    pedestrian_shape,
)
from tests.detector.cameras import scene_b
from tests.detector.clips import Clip

FPS = 15.0
WALK_MPS = 1.4


@pytest.fixture(scope="module")
def model():
    return default_model()


def walker(forward_m: float, lateral_m: float, t_s: float, heading_rad: float = math.pi / 2):
    """A 1.75 m pedestrian at forward distance ``forward_m`` walking at 1.4 m/s (y grows with t)."""
    dy = WALK_MPS * t_s * math.sin(heading_rad)
    dx = WALK_MPS * t_s * math.cos(heading_rad)
    return pedestrian_shape(
        forward_m + dx, lateral_m + dy, heading_rad, 0.5, 1.75, 0.7, 2 * math.pi * 0.9 * t_s
    )


def test_walking_pedestrian_is_detected_at_its_distance_as_a_pedestrian(model):
    cam = scene_b()
    clip = Clip(cam, seed=1)
    det = Detector(cam, model=model)
    clip.warm_up(det)
    forward_m = 10.0
    n_frames = 45
    good, ids = 0, []
    for k in range(n_frames):
        detections = det.process(clip.frame([walker(forward_m, -2.5, k / FPS)]))
        assert all(isinstance(d, Detection) for d in detections)
        targets = [d for d in detections if d.p_target >= 0.5]
        if len(detections) == 1 and len(targets) == 1:
            d = targets[0]
            ids.append(d.track_id)
            if abs(d.features[3] - forward_m) <= 0.1 * forward_m and d.cls == "pedestrian":
                good += 1
            assert d.probabilities.shape == (len(CLASSES),)
            assert d.p_target == pytest.approx(1.0 - d.probabilities[CLASSES.index("noise")])
            assert d.features[4] == cam.tilt_deg and d.features[5] == cam.height_m
    assert good >= 0.8 * n_frames
    # one object, one track
    assert len(set(ids)) == 1
    assert det.tracker.is_confirmed(ids[0])
    assert det.is_target(detections)


@pytest.mark.parametrize("tracking", [True, False])
def test_detections_built_at_once_are_the_constructors_own(model, tracking):
    # the detector builds Detections with all fields at once (detector._detection), not through
    # the frozen dataclass's __init__: the same fields, values, equality, and frozen still
    cam = scene_b()
    clip = Clip(cam, seed=1)
    det = Detector(cam, model=model, tracking=tracking)
    clip.warm_up(det)
    found = [d for k in range(10) for d in det.process(clip.frame([walker(10.0, -2.5, k / FPS)]))]
    assert len(found) >= 8
    names = [f.name for f in dataclasses.fields(Detection)]
    for d in found:
        assert list(vars(d)) == names and d == Detection(**vars(d))
        assert (d.track_cls is None) == (not tracking) and dataclasses.replace(d) == d
        with pytest.raises(dataclasses.FrozenInstanceError):
            d.cls = "noise"


def test_border_regions_and_far_regions_are_not_returned(model):
    cam = scene_b()
    clip = Clip(cam, seed=2)
    det = Detector(cam, model=model, max_distance_m=25.0)
    clip.warm_up(det)
    # entering at the right edge of the frame: segmented, flagged, not classified
    for k in range(4):
        detections = det.process(clip.frame([walker(10.0, -4.9, k / FPS)]))
    assert len(det.last_regions) >= 1 and det.last_regions.touches_border.all()
    assert detections == []

    # a pedestrian 22 m away is beyond a 20 m limit and within the paper's 25 m
    distances = {}
    for limit_m in (20.0, 25.0):
        clip = Clip(cam, seed=3)
        det = Detector(cam, model=model, max_distance_m=limit_m)
        clip.warm_up(det)
        found = [det.process(clip.frame([walker(22.0, 0.0, k / FPS)])) for k in range(8)]
        assert all(len(d) <= 1 for d in found)
        distances[limit_m] = [d[0].features[3] for d in found if d]
    assert distances[20.0] == []
    assert len(distances[25.0]) >= 6 and all(abs(d - 22.0) < 2.2 for d in distances[25.0])


@pytest.mark.parametrize("crop_to_range", [False, True])
def test_regions_without_a_ground_point_are_not_returned(model, crop_to_range):
    # tilt 5 deg puts the horizon at row ~90; a bright thing moving above it has no distance
    cam = scene_b(tilt_deg=5.0)
    assert 60 < cam.horizon_row_px < 120
    clip = Clip(cam, seed=4)
    det = Detector(cam, model=model, crop_to_range=crop_to_range)
    clip.warm_up(det, n=40)
    for k in range(4):
        img = clip.frame()
        img[20:60, 60 + 10 * k : 90 + 10 * k] = 200
        detections = det.process(img)
    if crop_to_range:  # above the band where a target within range can be: not even segmented
        assert det.crop.top_px > 60 and len(det.last_regions) == 0
    else:
        assert len(det.last_regions) == 1 and not det.last_regions.touches_border[0]
    assert detections == []


def test_reset_background_after_a_lamp_switch(model):
    cam = scene_b()
    clip = Clip(cam, seed=5)
    det = Detector(cam, model=model)
    clip.warm_up(det)
    clip.background *= 2.0  # the lamp in view switches on
    det.reset_background()
    for _ in range(5):
        assert det.process(clip.frame()) == []
    assert det.last_regions.foreground_fraction < 0.01


def test_numpy_probabilities_equal_the_models_own(model):
    cam = scene_b()
    fast = numpy_predict_proba(model, cam)
    assert fast is not None
    rng = np.random.default_rng(0)
    X = np.column_stack(
        [
            rng.uniform(0.1, 5, 500),
            rng.uniform(0.1, 3, 500),
            rng.uniform(0.01, 10, 500),
            rng.uniform(2, 30, 500),
            np.full(500, 22.0),
            np.full(500, 3.1),
        ]
    )
    np.testing.assert_allclose(fast(X), model.predict_proba(X), atol=1e-9, rtol=0)


def test_detector_falls_back_to_predict_proba_for_other_models():
    # any fitted classifier with a 'noise' class works; its probabilities come from predict_proba
    rng = np.random.default_rng(0)
    X = np.column_stack(
        [
            rng.uniform(0.1, 3, 400),
            rng.uniform(0.1, 2.5, 400),
            rng.uniform(0.05, 5, 400),
            rng.uniform(3, 25, 400),
            np.full(400, 22.0),
            np.full(400, 3.1),
        ]
    )
    y = np.where(X[:, 1] > 1.2, "pedestrian", "noise")
    other = LogisticRegression().fit(X, y)
    cam = scene_b()
    assert numpy_predict_proba(other, cam) is None
    det = Detector(cam, model=other)
    clip = Clip(cam, seed=6)
    clip.warm_up(det, n=60)
    detections = [det.process(clip.frame([walker(10.0, -1.0, k / FPS)])) for k in range(6)]
    found = [d[0] for d in detections if len(d) == 1]
    assert len(found) >= 4
    for d in found:
        np.testing.assert_allclose(d.probabilities, other.predict_proba(d.features[None])[0])
        assert d.cls in ("noise", "pedestrian")


def test_detector_rejects_bad_frames_and_settings(model):
    cam = scene_b()
    det = Detector(cam, model=model)
    with pytest.raises(ValueError, match=r"shape \(240, 320\)"):
        det.process(np.zeros((240, 424), np.uint8))
    with pytest.raises(ValueError, match="uint8"):
        det.process(np.zeros((240, 320), np.float32))
    with pytest.raises(ValueError, match="max_distance_m"):
        Detector(cam, model=model, max_distance_m=0.0)
    with pytest.raises(ValueError, match="target_threshold"):
        Detector(cam, model=model, target_threshold=1.5)


def test_is_target_uses_the_threshold(model):
    cam = scene_b()
    det = Detector(cam, model=model, target_threshold=0.7)
    make = lambda p: Detection((0, 0, 1, 1), np.zeros(6), "pedestrian", np.zeros(5), p, None)  # noqa: E731
    assert not det.is_target([])
    assert not det.is_target([make(0.69)])
    assert det.is_target([make(0.69), make(0.7)])


# ------------------------------------------------- optimised path = reference
def reference_process(camera, model, segmenter, tracker, frame, max_distance_m=25.0):
    """The detector's steps done the straightforward way: whole arrays, scikit-learn's predict_proba."""
    regions = segmenter.apply(frame)
    boxes, areas = regions.boxes_px, regions.areas_px
    feats, valid = region_features(camera, boxes, areas)

    def lit(body_box, spot_box):  # a light spot: brighter than the ground was and than the object
        spot, body = segmenter.brightness_dn(spot_box), segmenter.brightness_dn(body_box)
        return spot is not None and body is not None and spot[0] - max(spot[1], body[0]) >= MIN_SPOT_BRIGHTENING_DN

    parts = divide_regions(camera, regions.contours, boxes, areas, feats, valid, lit=lit)
    # a border region counts only as an object divided off it clear of the border
    ob = parts.boxes_px
    clear = np.all(
        (ob[:, :2] > 0) & (ob[:, :2] + ob[:, 2:] < (camera.width_px, camera.height_px)), axis=1
    )
    inner = ~regions.touches_border | (parts.divided & clear)
    keep = inner & parts.valid & (parts.features[:, 3] <= max_distance_m)
    feats, boxes = parts.features[keep], parts.boxes_px[keep]
    proba = model.predict_proba(feats) if len(feats) else np.zeros((0, len(CLASSES)))
    p_target = 1.0 - proba[:, CLASSES.index("noise")]
    ids = tracker.update(boxes, p_target >= 0.5)
    labels = np.asarray(model.classes_)[proba.argmax(axis=1)]
    detections = [
        (tuple(int(v) for v in box), f, str(c), p, i)
        for box, f, c, p, i in zip(boxes, feats, labels, proba, ids, strict=True)
    ]
    return detections, int(np.count_nonzero(parts.divided))


def test_optimised_detector_equals_the_straightforward_computation(model):
    # a distorted lens (undistortion path), walkers, a cyclist with a headlight spot in front
    # (division) and bursts of many specks (past the plain-Python sizes: the vectorised paths);
    # on the per-frame path (tracks join fragments, which the reference does not)
    cam = scene_b(k1=-0.08, k2=0.01)
    clip = Clip(cam, seed=7)
    rng = np.random.default_rng(7)
    det = Detector(cam, model=model, tracking=False)
    reference_tracker = Tracker()
    reference_tracker.SCALAR_MAX_PAIRS = 0  # score every pair matrix with numpy
    reference_segmenter = Segmenter()
    n_regions, n_divided, compared = [], 0, 0
    for k in range(100):
        t_s = k / FPS
        shapes = []
        if k >= 40:
            shapes = [
                walker(9.0, -2.5, t_s - 40 / FPS),
                walker(14.0, 2.0, t_s - 40 / FPS, heading_rad=-math.pi / 2),
                cyclist_shape(6.0 + 4.0 * (t_s - 40 / FPS), 0.5, 0.0, 0.6, 1.7, 1.8, 3.0 * t_s),
                ground_spot_shape(8.5 + 4.0 * (t_s - 40 / FPS), 0.5, 0.0, 1.6, 1.2),
            ]
        # the headlight's spot is brighter than the cyclist (a light spot: division only then)
        img = clip.frame(shapes, levels_dn=[150, 150, 120, 220][: len(shapes)])
        if k >= 40 and k % 4 == 0:
            for x, y in rng.uniform((20, 100), (300, 225), (24, 2)).astype(int):
                img[y : y + 11, x : x + 11] = 220
        got = det.process(img)
        want, divided = reference_process(cam, model, reference_segmenter, reference_tracker, img)
        n_regions.append(len(det.last_regions))
        assert len(got) == len(want), k
        for d, (box, feats, cls, proba, track_id) in zip(got, want, strict=True):
            assert d.box_px == box and d.cls == cls and d.track_id == track_id, k
            np.testing.assert_allclose(d.features, feats, rtol=1e-12, atol=1e-12)
            np.testing.assert_allclose(d.probabilities, proba, rtol=0, atol=1e-9)
            assert d.p_target == pytest.approx(1.0 - proba[CLASSES.index("noise")], abs=1e-9)
            compared += 1
        n_divided += divided
    # the clip did exercise both sizes of frame, and the division
    print(f"regions per frame up to {max(n_regions)}, {compared} detections, {n_divided} divided")
    assert max(n_regions) > SCALAR_MAX_REGIONS and compared > 100 and n_divided > 0
