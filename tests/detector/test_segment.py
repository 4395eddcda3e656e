"""Segmentation (CLAHE, MOG2, shadow cut, morphology, contours, filters) and region division."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from detector.camera import CameraModel
from detector.contours import contour_boxes_and_areas
from detector.divide import DivisionParams, divide_regions
from detector.features import region_features
from detector.segment import Regions, Segmenter, SegmenterParams
from detector.split import split_object_and_spot
from detector.train.shapes import pedestrian_shape, silhouette_mask
from tests.detector.cameras import scene_b

H_PX, W_PX = 240, 320
BACKGROUND_DN = 40.0
NOISE_DN = 3.0


class Scene:
    """Dark noisy static background; draws rectangles / masks at given brightness each frame."""

    def __init__(self, seed: int = 0, base_dn: float = BACKGROUND_DN) -> None:
        self.rng = np.random.default_rng(seed)
        ramp = np.linspace(-8, 8, W_PX)[
            None, :
        ]  # some structure, so CLAHE has something to equalise
        self.background = base_dn + ramp + self.rng.normal(0, 2, (H_PX, W_PX))

    def frame(self, rects=(), level_dn: float = 180.0, gain: float = 1.0) -> np.ndarray:
        img = self.background * gain + self.rng.normal(0, NOISE_DN, (H_PX, W_PX))
        for x, y, w, h in rects:
            x0, y0 = max(x, 0), max(y, 0)
            img[y0 : y + h, x0 : x + w] = level_dn + self.rng.normal(
                0, NOISE_DN, img[y0 : y + h, x0 : x + w].shape
            )
        return np.clip(img, 0, 255).astype(np.uint8)

    def shadow_frame(self, rect, factor: float) -> np.ndarray:
        """The background with a darker copy (factor x) of itself under ``rect``: a moving shadow."""
        x, y, w, h = rect
        img = self.background + self.rng.normal(0, NOISE_DN, (H_PX, W_PX))
        img[y : y + h, x : x + w] *= factor
        return np.clip(img, 0, 255).astype(np.uint8)


def warmed_up(scene: Scene, params: SegmenterParams | None = None, n: int = 30) -> Segmenter:
    seg = Segmenter(params or SegmenterParams())
    for _ in range(n):
        seg.apply(scene.frame())
    return seg


def match_box(regions: Regions, rect, tol_px: int = 2) -> int | None:
    """Index of the region whose box equals ``rect`` grown by the 1 px dilation, within tol_px per edge."""
    x, y, w, h = rect
    want = np.array([x - 1, y - 1, x + w, y + h])
    got = np.column_stack(
        [regions.boxes_px[:, :2], regions.boxes_px[:, :2] + regions.boxes_px[:, 2:] - 1]
    )
    hits = np.flatnonzero(np.all(np.abs(got - want) <= tol_px, axis=1))
    return int(hits[0]) if len(hits) else None


# --------------------------------------------------------------- segmentation
def test_moving_rectangles_found_with_their_boxes():
    scene = Scene(1)
    seg = warmed_up(scene)
    for i in range(8):
        rects = [(50 + 4 * i, 80, 20, 50), (250 - 5 * i, 120, 16, 40)]
        regions = seg.apply(scene.frame(rects))
        assert len(regions) == 2, regions.boxes_px
        for rect in rects:
            k = match_box(regions, rect)
            assert k is not None, (rect, regions.boxes_px)
            assert not regions.touches_border[k]
            # Green's-theorem area of a filled rectangle is (w-1)(h-1); dilation adds a ring
            assert (
                0.8 * rect[2] * rect[3] < regions.areas_px[k] < 1.3 * (rect[2] + 2) * (rect[3] + 2)
            )
        drawn_px = sum(w * h for *_, w, h in rects)
        assert regions.foreground_fraction == pytest.approx(drawn_px / (H_PX * W_PX), rel=0.25)
        assert regions.mask.shape == (H_PX, W_PX) and regions.mask.dtype == np.uint8
        assert (
            len(regions.contours)
            == len(regions)
            == len(regions.areas_px)
            == len(regions.touches_border)
        )
        assert regions.boxes_px.dtype == np.int32


def test_border_touching_regions_are_flagged_not_dropped():
    scene = Scene(2)
    seg = warmed_up(scene)
    for i in range(5):
        regions = seg.apply(
            scene.frame(
                [(-10, 60 + 2 * i, 30, 50), (150, 100 + 2 * i, 20, 50), (200, 200 + i, 25, 60)]
            )
        )
    assert len(regions) == 3
    left = np.flatnonzero(regions.boxes_px[:, 0] == 0)
    bottom = np.flatnonzero(regions.boxes_px[:, 1] + regions.boxes_px[:, 3] == H_PX)
    middle = match_box(regions, (150, 108, 20, 50))
    assert len(left) == 1 and regions.touches_border[left[0]]
    assert len(bottom) == 1 and regions.touches_border[bottom[0]]
    assert middle is not None and not regions.touches_border[middle]


@pytest.mark.parametrize("n_specks", [1, 60])  # few contours and many: both code paths
def test_tiny_and_sparse_regions_are_dropped(n_specks):
    scene = Scene(3)
    seg = warmed_up(scene)
    min_area_px = SegmenterParams().min_area_fraction * H_PX * W_PX  # 76.8 px
    grid = [(x, y) for y in range(140, 230, 18) for x in range(10, 300, 24)]  # 12 px apart at least
    speck_xy = grid[:n_specks]
    for i in range(5):
        specks = [(int(x) + 3 * i, int(y), 6, 6) for x, y in speck_xy]
        img = scene.frame([*specks, (120 + 3 * i, 50, 14, 14)])
        # a thin diagonal stroke: area above the size limit, extent below 0.2
        cv2.line(img, (200 + 3 * i, 30), (260 + 3 * i, 110), 200, 3)
        regions = seg.apply(img)
    assert len(regions) == 1
    k = match_box(regions, (132, 50, 14, 14))
    assert k is not None and regions.areas_px[k] >= min_area_px
    # the stroke and the specks were foreground, just filtered out
    assert regions.foreground_fraction * H_PX * W_PX > 14 * 14 + 150 + 20 * n_specks


def test_shadow_is_cut_but_would_be_foreground_without_the_cut():
    shadow_px = 60 * 80
    fractions = {}
    for cut in (170, 100):
        scene = Scene(4, base_dn=100.0)  # a lit road, so a shadow is well above the noise
        seg = warmed_up(scene, SegmenterParams(shadow_cut=cut))
        # the shadow jumps to fresh background each frame, so MOG2 never learns it
        runs = [
            seg.apply(scene.shadow_frame((10 + 75 * i, 60, 60, 80), factor=0.6)) for i in range(4)
        ]
        fractions[cut] = [r.foreground_fraction * H_PX * W_PX / shadow_px for r in runs]
        counts = [len(r) for r in runs]
        if cut == 170:
            assert counts == [0, 0, 0, 0]
    # MOG2 labels the darker blob shadow (127): removed by the 170 cut, kept by a 100 one
    assert max(fractions[170]) < 0.02  # a few noise specks, no region
    assert min(fractions[100]) > 0.8


def test_reset_forgets_the_background_when_the_lamp_switches_on():
    outcomes = {}
    for do_reset in (False, True):
        scene = Scene(5)
        # a long-settled model learns slowly (rate 1 / frames seen), as in a lamp at night
        seg = warmed_up(scene, n=200)
        if do_reset:
            seg.reset()
        outcomes[do_reset] = [
            seg.apply(scene.frame(gain=2.5)).foreground_fraction for _ in range(5)
        ]
    # without a reset the brighter scene is one huge foreground region frame after frame
    assert min(outcomes[False]) > 0.3
    assert max(outcomes[True]) < 0.01


def test_objects_are_found_again_after_a_reset():
    scene = Scene(6)
    seg = warmed_up(scene)
    seg.reset()
    for _ in range(10):
        seg.apply(scene.frame(gain=2.0))
    for i in range(4):
        rect = (40 + 60 * i, 70, 20, 50)
        regions = seg.apply(scene.frame([rect], level_dn=250, gain=2.0))
        assert len(regions) == 1 and match_box(regions, rect) is not None, regions.boxes_px


def test_bad_params_and_frames_raise_clear_errors():
    with pytest.raises(ValueError, match="shadow_cut"):
        SegmenterParams(shadow_cut=300)
    with pytest.raises(ValueError, match="min_extent"):
        SegmenterParams(min_extent=1.5)
    with pytest.raises(ValueError, match="clahe_tile_px"):
        SegmenterParams(clahe_tile_px=0)
    seg = Segmenter()
    with pytest.raises(ValueError, match="grayscale uint8"):
        seg.apply(np.zeros((H_PX, W_PX, 3), np.uint8))
    with pytest.raises(ValueError, match="float64"):
        seg.apply(np.zeros((H_PX, W_PX)))


@pytest.mark.parametrize("n_blobs", [3, 200])
def test_contour_boxes_and_areas_equal_opencv(n_blobs):
    rng = np.random.default_rng(n_blobs)
    mask = np.zeros((H_PX, W_PX), np.uint8)
    for _ in range(n_blobs):
        centre = (int(rng.integers(0, W_PX)), int(rng.integers(0, H_PX)))
        axes = (int(rng.integers(0, 12)), int(rng.integers(0, 12)))
        cv2.ellipse(mask, centre, axes, float(rng.uniform(0, 180)), 0, 360, 255, -1)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    boxes, areas = contour_boxes_and_areas(contours)
    np.testing.assert_array_equal(boxes, np.array([cv2.boundingRect(c) for c in contours]))
    np.testing.assert_allclose(areas, [cv2.contourArea(c) for c in contours], atol=1e-9)


# ------------------------------------------------------------------- division
def ground_ellipse_uv(camera: CameraModel, centre_xy_m, radii_m) -> np.ndarray:
    """Projected outline of a flat ellipse on the ground (a light spot), (K, 2) px."""
    ang = np.linspace(0, 2 * math.pi, 48, endpoint=False)
    pts = np.column_stack(
        [
            centre_xy_m[0] + radii_m[0] * np.cos(ang),
            centre_xy_m[1] + radii_m[1] * np.sin(ang),
            np.zeros_like(ang),
        ]
    )
    return camera.project(pts)


def region_of(camera: CameraModel, shape=None, spot=None):
    """Dilated mask of a walker silhouette and/or a light spot -> its largest region's inputs for division."""
    mask = np.zeros((H_PX, W_PX), np.uint8)
    if shape is not None:
        sil = silhouette_mask(camera, shape)
        x0, y0 = sil.offset_px
        mask[y0 : y0 + sil.mask.shape[0], x0 : x0 + sil.mask.shape[1]] |= sil.mask
    if spot is not None:
        cv2.fillPoly(mask, [np.round(ground_ellipse_uv(camera, *spot)).astype(np.int32)], 255)
    mask = cv2.dilate(mask, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3)))
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    assert len(contours) == 1, "walker and spot must form one region"
    boxes, areas = contour_boxes_and_areas(contours)
    k = 0
    feats, valid = region_features(camera, boxes[k : k + 1], areas[k : k + 1])
    return [contours[k]], boxes[k : k + 1], areas[k : k + 1], feats, valid


WALKER = dict(width_m=0.5, height_m=1.75, step_m=0.6, gait_phase_rad=0.4)


@pytest.mark.parametrize(
    "spot_offset_m, heading_rad",
    [
        ((0.0, 1.05), math.pi / 2),  # walking across, flashlight spot beside the feet
        ((0.0, -1.05), -math.pi / 2),  # walking across the other way
        ((-0.95, 0.0), math.pi),  # walking towards the camera: spot in front of (below) the feet
        ((1.0, 0.0), 0.0),  # walking away: spot behind the feet, beside the legs in the image
    ],
)
def test_division_cuts_a_pedestrian_from_its_light_spot(spot_offset_m, heading_rad):
    cam = scene_b()
    x_m, y_m = 10.0, 0.3
    walker = pedestrian_shape(x_m, y_m, heading_rad, **WALKER)
    spot = ((x_m + spot_offset_m[0], y_m + spot_offset_m[1]), (0.8, 0.9))
    merged = region_of(cam, walker, spot)
    alone = region_of(cam, walker)
    assert merged[2][0] > 1.5 * alone[2][0]  # one region: walker and spot joined
    merged_feats = merged[3][0]
    # the merged region's features are far off the pedestrian's (the premise of the paper's division)
    assert merged_feats[0] > 1.8 * alone[3][0, 0] or merged_feats[2] > 1.8 * alone[3][0, 2]

    out = divide_regions(cam, *merged)
    assert out.divided.tolist() == [True]
    assert len(out.spot_boxes_px) == 1
    width_m, height_m, _, distance_m = out.features[0, :4]
    assert distance_m == pytest.approx(x_m, rel=0.10)
    assert height_m == pytest.approx(WALKER["height_m"], rel=0.15)
    assert width_m == pytest.approx(alone[3][0, 0], rel=0.30)
    # the object's box lies inside the merged box and the spot's box is flat
    bx, by, bw, bh = out.boxes_px[0]
    mx, my, mw, mh = merged[1][0]
    assert mx <= bx and my <= by and bx + bw <= mx + mw and by + bh <= my + mh
    sx, sy, sw, sh = out.spot_boxes_px[0]
    assert sh < 0.7 * sw


def test_division_skips_only_regions_whose_object_would_be_beyond_range_too():
    """``divide_rows(..., beyond_m)``, the detector's saving on a camera without distortion: the
    object part of a divided region is never nearer than the region (its bottom row is at or
    above the region's), so a region beyond range needs no division: its object is dropped too."""
    from detector.divide import divide_rows
    from detector.features import RegionGeometry

    cam = scene_b()
    assert not cam.has_distortion
    geometry = RegionGeometry(cam)
    spots = [((0.0, 1.05), math.pi / 2), ((-0.95, 0.0), math.pi), ((1.0, 0.0), 0.0)]
    beyond = 0
    for x_m in (14.0, 22.0, 26.0, 28.0, 30.0):
        for offset_m, heading_rad in spots:
            walker = pedestrian_shape(x_m, 0.3, heading_rad, **WALKER)
            contours, boxes, areas, feats, _ = region_of(
                cam, walker, ((x_m + offset_m[0], 0.3 + offset_m[1]), (0.8, 0.9))
            )
            region_m = feats[0, 3]
            rows = [feats[0].tolist()]
            divided, _ = divide_rows(geometry, contours, boxes.tolist(), areas.tolist(), rows)
            assert divided == [0] and rows[0][3] >= region_m  # the object part: not nearer
            rows = [feats[0].tolist()]
            skipped, _ = divide_rows(
                geometry, contours, boxes.tolist(), areas.tolist(), rows, beyond_m=25.0
            )
            assert skipped == ([] if region_m > 25.0 else [0])
            beyond += region_m > 25.0
    assert beyond >= 4


@pytest.mark.parametrize(
    "heading_rad, phase_rad", [(math.pi / 2, 0.0), (math.pi / 2, 1.5), (0.3, 1.0), (math.pi, 2.0)]
)
def test_division_leaves_a_lone_pedestrian_whole(heading_rad, phase_rad):
    cam = scene_b()
    walker = pedestrian_shape(12.0, -0.5, heading_rad, 0.55, 1.8, 0.75, phase_rad)
    contours, boxes, areas, feats, valid = region_of(cam, walker)
    out = divide_regions(cam, contours, boxes, areas, feats, valid, DivisionParams(max_extent=1.0))
    assert out.divided.tolist() == [False]
    np.testing.assert_array_equal(out.boxes_px, boxes)
    np.testing.assert_array_equal(out.features, feats)
    assert len(out.spot_boxes_px) == 0


def test_split_rejects_shapes_without_a_flat_base():
    rect = np.zeros((40, 20), np.uint8)
    rect[:, :] = 1
    assert split_object_and_spot(rect) is None
    # an upright blob with an arm sticking out sideways at mid height: not a ground spot
    arm = np.zeros((60, 40), np.uint8)
    arm[:, 10:22] = 1
    arm[20:26, 22:40] = 1
    assert split_object_and_spot(arm) is None
    # the same blob standing on a flat bright ellipse: split, the object keeps its full height
    spot = np.zeros((60, 40), np.uint8)
    spot[:50, 10:22] = 1
    cv2.ellipse(spot, (24, 52), (15, 6), 0, 0, 360, 1, -1)
    parts = split_object_and_spot(spot)
    assert parts is not None
    body, flat = parts
    rows = np.flatnonzero(body.any(axis=1))
    assert rows[0] == 0 and 46 <= rows[-1] <= 53
    assert np.count_nonzero(body & flat) == 0 and np.count_nonzero(body | flat) == np.count_nonzero(
        spot
    )


def test_division_params_are_validated():
    with pytest.raises(ValueError, match="max_extent"):
        DivisionParams(max_extent=0.0)
    with pytest.raises(ValueError, match="wide_row_factor"):
        DivisionParams(wide_row_factor=1.0)


def test_few_and_many_contour_paths_give_the_same_regions(monkeypatch):
    import detector.contours as contour_sets

    def run() -> list[Regions]:
        scene = Scene(9)
        seg = warmed_up(scene)
        out = []
        for i in range(6):
            rects = [(20 + 40 * k + 2 * i, 40 + 30 * (k % 5), 8 + k, 12 + 2 * k) for k in range(7)]
            img = scene.frame([*rects, (-10, 190 + 2 * i, 30, 40)])  # the last touches the border
            cv2.line(img, (200 + 3 * i, 30), (260 + 3 * i, 110), 200, 3)  # sparse: dropped
            out.append(seg.apply(img))
        return out

    few = run()
    monkeypatch.setattr(contour_sets, "FEW_CONTOURS", 0)  # every frame through the vectorised path
    many = run()
    assert sum(len(r) for r in few) >= 6 * 6
    for a, b in zip(few, many, strict=True):
        np.testing.assert_array_equal(a.boxes_px, b.boxes_px)
        np.testing.assert_allclose(a.areas_px, b.areas_px, rtol=0, atol=1e-9)
        np.testing.assert_array_equal(a.touches_border, b.touches_border)
        assert a.boxes_px.dtype == b.boxes_px.dtype == np.int32 and a.touches_border.any()
        assert [len(c) for c in a.contours] == [len(c) for c in b.contours]


def test_few_contour_edge_flags_and_lists_are_the_arrays_own():
    """On a crop whose top is not the frame's (and whose other edges are), the per-frame path's
    Python edge test gives ``_edges``' flags, and ``Regions.lists`` the arrays' values."""
    from detector.roi import Crop

    scene = Scene(4)
    seg = Segmenter(crop=Crop(60, H_PX, 0, W_PX, H_PX, W_PX, (0, H_PX, 0, W_PX), (8, 8)))
    for _ in range(30):
        seg.apply(scene.frame())
    # across the crop's top; at the frame's bottom, left, right; across the top at the left; inside
    rects = [(100, 40, 20, 50), (150, 200, 20, 40), (0, 120, 15, 30), (300, 150, 20, 30)]
    rects += [(0, 30, 25, 60), (220, 110, 20, 40)]
    regions = seg.apply(scene.frame(rects))
    assert len(regions) == 6 and regions.lists is not None
    touches, cut = seg._edges(regions.boxes_px)
    np.testing.assert_array_equal(regions.touches_border, touches)
    np.testing.assert_array_equal(regions.cut_by_crop, cut)
    assert touches.sum() == 4 and cut.sum() == 2 and (touches & cut).sum() == 1
    assert regions.lists == (
        regions.boxes_px.tolist(),
        regions.areas_px.tolist(),
        regions.unusable.tolist(),
    )


def test_explicit_automatic_learning_rate_is_mog2s_own():
    """A caller judging only some frames passes the rate of the frames taken; on every frame it
    must be exactly what MOG2 picks by itself."""
    rng = np.random.default_rng(5)
    frames = []
    for k in range(40):
        img = np.clip(rng.normal(50, 4, (120, 160)), 0, 255).astype(np.uint8)
        cv2.rectangle(img, (10 + 3 * k, 40), (22 + 3 * k, 80), 200, -1)
        frames.append(img)
    own, explicit = Segmenter(), Segmenter()
    for k, frame in enumerate(frames):
        a = own.apply(frame).mask
        b = explicit.apply(frame, explicit.automatic_learning_rate(k)).mask
        assert np.array_equal(a, b), k
    assert explicit.history_frames == 500  # 500 frames at the default 15 frames/s
    assert explicit.automatic_learning_rate(1000) == 1.0 / explicit.history_frames
