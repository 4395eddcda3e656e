"""The detector's region of interest (detector.roi): which rows can hold a target within range,
and detections on the crop against those on the full frame."""

from __future__ import annotations

import math

import numpy as np
import pytest

from detector.camera import CameraModel
from detector.classes import TABLE1
from detector.detector import Detector
from detector.general_model import default_model
from detector.roi import (
    TALLEST_TARGET_M,
    Crop,
    band_bounds_px,
    band_top_row_px,
    morphology_margin_px,
    range_crop,
)
from detector.segment import Segmenter, SegmenterParams
from detector.train.shapes import (
    blob_shape,
    cyclist_shape,
    group_shape,
    pedestrian_shape,
    vehicle_shape,
)
from tests.detector.cameras import scene_b
from tests.detector.clips import Clip

RANGE_M = 25.0
SCENE_A = CameraModel(
    height_m=3.0, tilt_deg=13.0, focal_mm=3.67, sensor_w_mm=4.8, sensor_h_mm=3.6,
    width_px=424, height_px=240,
)  # fmt: skip
# the suburban scenario's lamp camera: scene A's lens on a 5.5 m pole, 15 deg, mild barrel distortion
SUBURBAN = SCENE_A.placed(height_m=5.5, tilt_deg=15.0, yaw_deg=-8.0, k1=-0.05)
SCENE_CD = CameraModel(
    height_m=5.0, tilt_deg=17.0, focal_mm=3.6, sensor_w_mm=3.45, sensor_h_mm=1.94,
    width_px=424, height_px=240,
)  # fmt: skip
# strong barrel distortion (the renderer bench's cheap lens), where the band's top row bends
BARREL = scene_b(height_m=6.0, tilt_deg=18.0, k1=-0.25, k2=0.06)
CAMERAS = {"scene A": SCENE_A, "suburban": SUBURBAN, "scene C/D": SCENE_CD, "barrel": BARREL}
FPS = 15.0
N_FRAMES = 40


@pytest.fixture(scope="module")
def model():
    return default_model()


def ground_xy(camera: CameraModel, forward_m: float, lateral_m: float) -> tuple[float, float]:
    """World (x, y) of the ground point ``forward_m`` ahead of the pole and ``lateral_m`` left."""
    h = camera.heading_unit
    x, y = camera.position_m[:2] + forward_m * h + lateral_m * np.array([-h[1], h[0]])
    return float(x), float(y)


def box_outline_m(camera, near_m, lateral_m, yaw_rad, length_m, width_m, height_m) -> np.ndarray:
    """Points along the 12 edges of a box standing on the ground whose nearest ground point is
    ``near_m`` ahead of the pole, turned ``yaw_rad`` from the camera's heading, (K, 3) world m."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    corners = np.array([[fx * length_m / 2, fy * width_m / 2] for fx in (-1, 1) for fy in (-1, 1)])
    turned = corners @ np.array([[c, -s], [s, c]]).T  # (forward, left) offsets from the centre
    centre_m = near_m - turned[:, 0].min()
    feet = [ground_xy(camera, centre_m + f, lateral_m + left) for f, left in turned]
    ends = [(*p, z) for p in feet for z in (0.0, height_m)]
    edges = [(a, b) for i, a in enumerate(ends) for b in ends[i + 1 :]]
    t = np.linspace(0.0, 1.0, 40)[:, None]
    return np.concatenate([np.asarray(a) * (1 - t) + np.asarray(b) * t for a, b in edges])


# ----------------------------------------------------------------- geometry
@pytest.mark.parametrize("name", CAMERAS)
def test_every_target_within_range_lies_in_the_band(name):
    camera = CAMERAS[name]
    first_row, left, right = band_bounds_px(camera, RANGE_M)
    crop = range_crop(camera, RANGE_M)
    assert crop.top_px <= first_row - morphology_margin_px(3, 1) - 1 and (left, right) == (
        0,
        camera.width_px,
    )
    rng = np.random.default_rng(0)
    van = TABLE1["vehicle"]
    # the worst case first: the largest van at the range's end, its diagonal along the heading
    # with its far top corner on the image's centre column; then targets of every class anywhere
    samples = [(RANGE_M, 0.0, -math.atan2(van.width_m[1], van.length_m[1]), van)]
    samples += [
        (
            rng.uniform(0.5, RANGE_M),
            rng.uniform(-15.0, 15.0),
            rng.uniform(-math.pi, math.pi),
            TABLE1[rng.choice(list(TABLE1))],
        )
        for _ in range(300)
    ]
    highest = math.inf
    for near_m, lateral_m, yaw_rad, size in samples:
        length_m, width_m, height_m = size.length_m[1], size.width_m[1], size.height_m[1]
        pts = box_outline_m(camera, near_m, lateral_m, yaw_rad, length_m, width_m, height_m)
        uv = camera.project(pts)
        # points far outside the view can fold back into it through the distortion polynomial
        ideal = camera.project(pts, distort=False)
        near_view = np.abs(ideal - (camera.cx_px, camera.cy_px)).max(axis=1) < camera.width_px
        seen = near_view & (np.abs(uv[:, 0] - camera.cx_px) < camera.width_px / 2) & (uv[:, 1] > -0.5)
        if np.any(seen):
            highest = min(highest, float(uv[seen, 1].min()))
    # no visible part of any target above the band's first row (pixel row r spans r - 0.5 .. r + 0.5)
    assert highest > first_row - 0.5, (highest, first_row)
    # and the band is tight: the largest targets at the range's end reach within 3 rows of its top
    assert highest < first_row + 3, (highest, first_row)


@pytest.mark.parametrize("name", CAMERAS)
def test_rows_above_the_crop_hold_no_target_within_range(name):
    camera = CAMERAS[name]
    crop = range_crop(camera, RANGE_M)
    above = np.column_stack(
        [np.arange(camera.width_px, dtype=float), np.full(camera.width_px, crop.top_px - 1.0)]
    )
    v_und = camera.undistort_pixels(above)[:, 1]
    assert np.all(v_und + 0.5 < band_top_row_px(camera, RANGE_M))
    # a ray through such a row passes a Table 1 top only beyond range: its height at the range's
    # end (plus a car's length) is above the tallest target
    depression = camera.depression_rad(v_und.max() + 0.5)
    assert camera.height_m - (RANGE_M + 4.6) * math.tan(depression) > TALLEST_TARGET_M


@pytest.mark.parametrize("name", CAMERAS)
def test_crop_is_equalised_on_the_full_frames_own_tiles(name):
    camera = CAMERAS[name]
    assert range_crop(camera, RANGE_M).clahe_share == 1.0  # by default: the whole frame
    crop = range_crop(camera, RANGE_M, equalise_tiles_only=True)
    tile_h = camera.height_px // 8
    top, bottom, left, right = crop.clahe_px
    nx, ny = crop.clahe_tiles
    # whole tiles of the full frame's grid, from at least half a tile above the crop: a pixel in a
    # tile's upper half interpolates with the tile above
    assert top % tile_h == 0 and (bottom - top) == ny * tile_h and bottom == camera.height_px
    assert (left, right, nx) == (0, camera.width_px, 8)
    assert top <= crop.top_px - tile_h / 2 or top == 0
    assert crop.top_px - top < 1.5 * tile_h
    assert crop.bottom_px == camera.height_px and 0.5 < crop.share <= crop.clahe_share
    # scene C/D's crop starts in the upper half of the first tile, which needs every tile
    assert crop.clahe_share < 1.0 or name == "scene C/D"


def test_equalised_tiles_are_the_full_frames_but_for_float_rounding():
    camera = SUBURBAN
    crop = range_crop(camera, RANGE_M, equalise_tiles_only=True)
    full, cropped = Segmenter(), Segmenter(crop=crop)
    rng = np.random.default_rng(5)
    ramp = np.linspace(20.0, 90.0, camera.height_px)[:, None]
    for _ in range(3):
        frame = np.clip(ramp + rng.normal(0, 8, (240, 424)), 0, 255).astype(np.uint8)
        full.apply(frame)
        cropped.apply(frame)
        a = full._equalised[crop.slices]
        b = cropped._equalised_crop
        differ = a != b
        assert np.abs(a.astype(int) - b).max() <= 1 and differ.mean() < 0.005, differ.mean()


def test_crop_is_the_full_frame_when_the_range_covers_it():
    # scene B sees a 2 m target at 25 m above its top row; a 1.8 m camera, any row can hold a target
    for camera in (scene_b(), scene_b(height_m=1.8, tilt_deg=2.0)):
        crop = range_crop(camera, RANGE_M)
        assert crop.is_full_frame and crop.clahe_tiles == (8, 8)
    # the paper's scene C/D range: a few rows left out, all of CLAHE's tiles needed
    far = range_crop(SCENE_CD, 50.0)
    assert 0 < far.top_px < 10 and far.clahe_share == 1.0 and far.clahe_tiles == (8, 8)
    with pytest.raises(ValueError, match="do not fit"):
        Crop(10, 300, 0, 320, 240, 320, (0, 240, 0, 320), (8, 8))
    seg = Segmenter(crop=range_crop(SCENE_A, RANGE_M))
    with pytest.raises(ValueError, match=r"crop is of \(240, 424\) frames"):
        seg.apply(np.zeros((240, 320), np.uint8))


# ---------------------------------------------------------- crop vs full frame
def targets(camera: CameraModel, t_s: float) -> list:
    """Table 1's targets, the largest at the range's end, each in its own columns and walking or
    riding along the camera's heading; every one's nearest ground point within 25 m."""
    away = math.radians(camera.yaw_deg)
    toward = away + math.pi
    return [
        pedestrian_shape(*ground_xy(camera, 8.0 + 1.4 * t_s, -2.0), away, 0.5, 1.75, 0.7, 6 * t_s),
        pedestrian_shape(
            *ground_xy(camera, 24.5 - 1.4 * t_s, 12.0), toward, 0.64, 2.0, 0.79, 5 * t_s
        ),
        cyclist_shape(*ground_xy(camera, 16.0 - 3.0 * t_s, 3.0), toward, 0.6, 1.9, 1.7, 3 * t_s),
        group_shape(
            *ground_xy(camera, 17.0 + 1.4 * t_s, -9.0),
            away,
            [(0.0, 0.6, 0.5, 1.8, 0.6, 6 * t_s), (0.1, -0.6, 0.5, 2.0, 0.6, 6 * t_s + 2)],
        ),
        # a 2 m van creeping toward the camera along the heading, its front at 22.7-21.4 m
        vehicle_shape(*ground_xy(camera, 25.0 - 0.5 * t_s, -1.5), toward, 1.8, 2.0, 4.6),
    ]


@pytest.mark.parametrize("name", ["scene A", "suburban"])
@pytest.mark.parametrize("tiles_only", [False, True])
def test_detections_on_the_crop_equal_those_on_the_full_frame(model, name, tiles_only):
    camera = CAMERAS[name]
    clip = Clip(camera, seed=11)
    cropped = Detector(camera, model=model, equalise_tiles_only=tiles_only)
    full = Detector(camera, model=model, crop_to_range=False)
    assert cropped.crop.share < 0.75 and full.crop.is_full_frame
    for _ in range(100):
        frame = clip.frame()
        assert cropped.process(frame) == full.process(frame) == []
    compared, same, classes = 0, 0, set()
    for k in range(N_FRAMES):
        frame = clip.frame(targets(camera, k / FPS))
        got, want = cropped.process(frame), full.process(frame)
        if not tiles_only:  # the full frame's equalisation: the same regions, box and class
            assert [(d.box_px, d.cls) for d in got] == [(d.box_px, d.cls) for d in want], k
            for d, w in zip(got, want, strict=True):
                np.testing.assert_allclose(d.features, w.features, rtol=1e-12)
                np.testing.assert_allclose(d.probabilities, w.probabilities, atol=1e-9)
        compared += len(want)
        same += len({(d.box_px, d.cls) for d in got} & {(d.box_px, d.cls) for d in want})
        classes |= {d.cls for d in want}
    # the five targets (the group as two people; the van, seen from the front, as a group or a
    # cyclist) in most frames
    print(f"{name}: {same} of {compared} detections the same, classes {sorted(classes)}")
    assert compared > 5 * N_FRAMES and {"pedestrian", "cyclist", "group"} <= classes
    assert same >= (0.97 if tiles_only else 1.0) * compared


def test_region_cut_by_the_crop_is_flagged_and_not_classified(model):
    camera = SCENE_A
    clip = Clip(camera, seed=12)
    det = Detector(camera, model=model)
    for _ in range(60):
        det.process(clip.frame())
    top = det.crop.top_px
    for k in range(4):
        # a 4 m tall pole-like thing 10 m away: feet in range, top far above any target's
        mast = blob_shape(*ground_xy(camera, 10.0, -1.0 + 0.3 * k), 0.0, 0.4, 4.0, 0.4)
        # someone right under the camera, cut by the frame's bottom edge
        near = pedestrian_shape(*ground_xy(camera, 3.0, 0.5), 0.0, 0.5, 1.75, 0.7, k)
        detections = det.process(clip.frame([mast, near]))
    regions = det.last_regions
    assert len(regions) == 2
    cut = int(np.flatnonzero(regions.cut_by_crop)[0])
    assert regions.boxes_px[cut][1] == top  # full-frame rows: its box starts at the crop's top row
    assert not regions.touches_border[cut]
    bottom = 1 - cut
    assert regions.touches_border[bottom] and not regions.cut_by_crop[bottom]
    assert sum(regions.boxes_px[bottom][1::2]) == camera.height_px
    assert detections == []


# ------------------------------------------------------- history in seconds
def seconds_to_forget(fps: float, params: SegmenterParams | None = None) -> float:
    """Seconds after the scene changes at once (new 8 px blocks: neither CLAHE nor the opening
    takes the change away) until MOG2 calls half as much of the frame foreground as at first."""
    rng = np.random.default_rng(3)
    seg = Segmenter(params or SegmenterParams(), fps=fps)
    before, after = (np.kron(rng.uniform(40, 120, (12, 16)), np.ones((8, 8))) for _ in range(2))
    for _ in range(int(25 * fps)):  # 25 s: past the automatic rate's ramp (half the history)
        seg.apply(np.clip(before + rng.normal(0, 2, before.shape), 0, 255).astype(np.uint8))
    first = None
    for k in range(int(60 * fps)):
        frame = np.clip(after + rng.normal(0, 2, after.shape), 0, 255).astype(np.uint8)
        fraction = seg.apply(frame).foreground_fraction
        first = fraction if first is None else first
        if fraction < first / 2:
            return k / fps
    return math.inf


def test_cameras_at_different_frame_rates_forget_at_the_same_speed():
    assert SegmenterParams().history_frames(15.0) == 500  # the paper implementation's 500 frames
    assert Segmenter(fps=25.0).history_frames == 833
    slow, fast = seconds_to_forget(15.0), seconds_to_forget(30.0)
    assert 1.0 < slow < 10.0
    # the same within a frame of the slower camera and 5 % (the noise differs)
    assert abs(fast - slow) <= 1 / 15.0 + 0.05 * slow, (slow, fast)
    # a history counted in frames would have the 30 frames/s camera forget twice as fast
    in_frames = seconds_to_forget(30.0, SegmenterParams(mog2_history_s=500 / 30.0))
    assert in_frames < 0.6 * slow, (in_frames, slow)


def test_motion_beyond_range_wakes_no_camera_on_whole_frames_either():
    """A lamp camera is kept at its full frame rate by motion where a target within range can
    appear (``Detector.motion_in_band``): on whole frames, a blob moving above the band makes
    regions but no such motion; inside the band it does, as on the crop."""
    camera = CameraModel(height_m=6.0, tilt_deg=20.0, focal_mm=3.6, sensor_w_mm=4.8, sensor_h_mm=3.6,
                         width_px=320, height_px=240)  # fmt: skip
    whole = Detector(camera, model=default_model(), crop_to_range=False)
    band = Detector(camera, model=default_model())
    top_px = band.crop.top_px
    assert whole.band == band.crop and 30 < top_px < 200
    rng = np.random.default_rng(0)
    background = (40 + rng.normal(0, 3, (240, 320))).clip(0, 255).astype(np.uint8)
    for _ in range(30):
        whole.process(background)
        band.process(background)
    seen = {}
    for where, (y0, y1) in {"above": (top_px - 28, top_px - 8), "inside": (200, 230)}.items():
        for k in range(3):
            frame = background.copy()
            frame[y0:y1, 40 + 12 * k : 60 + 12 * k] = 200
            whole.process(frame)
            band.process(frame)
        seen[where] = (len(whole.last_regions) > 0, whole.motion_in_band, band.motion_in_band)
        for _ in range(30):  # the blob gone and forgotten
            whole.process(background)
            band.process(background)
    assert seen["above"] == (True, False, False)
    assert seen["inside"] == (True, True, True)
