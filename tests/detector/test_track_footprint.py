"""Steep cameras: footprints on the ground, a car's pieces joined, still regions (ghosts) on no track.

Synthetic input: boxes made by projecting a car's corners through a steep camera, and tracks
fed by hand, so each rule is seen alone; and one synthetic video through the whole detector.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from detector.camera import CameraModel
from detector.features import RegionGeometry
from detector.ghosts import StillRegions
from detector.tracks.footprint import (
    STEEP_DEPRESSION_DEG,
    FootprintGeometry,
    FootprintJoiner,
    FootprintParams,
    is_steep,
    join_groups,
)
from detector.tracks.tracker import STILL_REASON, TrackSet

CAMERAS = Path(__file__).resolve().parents[2] / "scenarios" / "cameras"
CLASSES = ["noise", "pedestrian", "group", "cyclist", "vehicle"]
#: per-frame probabilities of no interest to these rules
PROBABILITIES = [0.6, 0.1, 0.1, 0.1, 0.1]


def steep_camera(**overrides) -> CameraModel:
    """The car-park clip's camera (10 m up, 50 degrees down) at 424 x 239 px, as the CLI runs it."""
    camera = CameraModel.from_yaml(CAMERAS / "realclip_carpark.yaml")
    return camera.placed(width_px=424, height_px=239, **overrides)


def car_box_px(camera: CameraModel, forward_m: float, right_m: float, heading_deg: float = 90.0,
               length_m: float = 4.4, width_m: float = 1.8, height_m: float = 1.5) -> list[int]:  # fmt: skip
    """Image box (x, y, w, h px) of a car standing at (forward, right) of the camera's ground
    frame, its length along ``heading_deg`` (90: along the camera's heading), through the camera
    model (camera at the world origin looking along +x: forward is world x, right is -y)."""
    a = math.radians(heading_deg)
    along = np.array([math.sin(a), -math.cos(a)])  # heading 90 deg: along +x (forward)
    across = np.array([-along[1], along[0]])
    centre = np.array([forward_m, -right_m])
    corners = [
        (*(centre + s * length_m / 2 * along + t * width_m / 2 * across), z)
        for s in (-1, 1) for t in (-1, 1) for z in (0.0, height_m)
    ]  # fmt: skip
    uv = camera.project(np.array(corners, np.float64))
    x0, y0 = np.floor(uv.min(axis=0)).astype(int)
    x1, y1 = np.ceil(uv.max(axis=0)).astype(int)
    return [int(x0), int(y0), int(x1 - x0), int(y1 - y0)]


def test_steep_means_every_row_looks_down_more_than_a_car_is_tall_for_its_length():
    assert STEEP_DEPRESSION_DEG == pytest.approx(math.degrees(math.atan(2.0 / 3.7)))
    assert is_steep(CameraModel.from_yaml(CAMERAS / "realclip_carpark.yaml"))
    # the paper's cameras, the lamps' (13-22 degrees) and the night walk's look along the street
    for name in ("scene_a", "scene_b", "scene_cd", "realclip_night_walk"):
        assert not is_steep(CameraModel.from_yaml(CAMERAS / f"{name}.yaml")), name
    camera = steep_camera()
    top_row_deg = camera.tilt_deg - camera.vertical_fov_deg / 2
    assert not is_steep(camera.placed(tilt_deg=camera.tilt_deg - top_row_deg + STEEP_DEPRESSION_DEG - 0.1))


def test_non_steep_cameras_build_none_of_it():
    camera = CameraModel.from_yaml(CAMERAS / "scene_cd.yaml")
    assert TrackSet(camera, CLASSES).footprint is None
    assert TrackSet(steep_camera(), CLASSES).footprint is not None


def test_a_cars_footprint_is_a_cars_size_where_its_upright_height_is_not():
    camera = steep_camera()
    geometry = RegionGeometry(camera)
    footprints = FootprintGeometry(camera, geometry, FootprintParams())
    for heading_deg in (90.0, 0.0, 45.0):
        box = car_box_px(camera, 8.0, 0.0, heading_deg)
        near_m, far_m, left_m, right_m = footprints.extents_m([box])[0]
        assert far_m - near_m <= FootprintParams().max_extent_m
        assert right_m - left_m <= FootprintParams().max_extent_m
    # the paper's geometry, an upright body on the bottom row, sees the car along the view as tall
    box = car_box_px(camera, 8.0, 0.0, 90.0)
    assert geometry.rows([box], [box[2] * box[3] * 0.8])[0][1] > 2.5


def test_pieces_of_one_car_join_and_two_cars_apart_do_not():
    camera = steep_camera()
    footprints = FootprintGeometry(camera, RegionGeometry(camera), FootprintParams())
    x, y, w, h = car_box_px(camera, 8.0, 0.0)
    # roof, windscreen, bonnet: three pieces with gaps between them
    pieces = [[x, y, w, h // 3 - 2], [x + 3, y + h // 3 + 2, w - 6, h // 4], [x, y + 2 * h // 3, w, h - 2 * h // 3]]
    assert join_groups(pieces, footprints.extents_m, FootprintParams().max_extent_m) == [[0, 1, 2]]
    other = car_box_px(camera, 8.0, 6.0)  # a car parked 6 m to the right
    assert join_groups([pieces[0], other], footprints.extents_m, FootprintParams().max_extent_m) == []


def test_a_car_in_changing_pieces_moving_under_a_steep_camera_is_one_track():
    camera = steep_camera()
    tracks = TrackSet(camera, CLASSES, keep_ended=True)
    geometry = tracks.geometry
    rng = np.random.default_rng(3)
    ids = set()
    for k in range(36):  # 3 s at 12 frames/s, 3 m/s along the view
        x, y, w, h = car_box_px(camera, 6.0 + 0.25 * k, -0.5)
        cuts = sorted(rng.choice(np.arange(4, h - 4), size=int(rng.integers(1, 4)), replace=False).tolist())
        edges = [0, *cuts, h]
        # each piece keeps a random share of its width: outlines change from frame to frame
        pieces = []
        for top, bottom in zip(edges, edges[1:], strict=False):
            if bottom - top < 3:
                continue
            shrink = int(rng.integers(0, w // 4))
            pieces.append([x + shrink, y + top + 1, w - 2 * shrink, bottom - top - 2])
        areas = [0.7 * pw * ph for _, _, pw, ph in pieces]
        rows = geometry.rows(pieces, areas)
        prepared = tracks.prepare(pieces, areas, rows)
        views = tracks.update(prepared, [PROBABILITIES] * len(prepared.rows))
        ids.update(v.track_id for v in views)
    assert len(ids) == 1
    assert len(tracks.tracks) + len(tracks.ended) == 1


def test_still_regions_follow_no_track_and_are_never_targets():
    camera = steep_camera()
    tracks = TrackSet(camera, CLASSES, keep_ended=True)
    geometry = tracks.geometry
    ghost = car_box_px(camera, 7.0, 2.5)
    for _ in range(30):
        rows = geometry.rows([ghost], [0.8 * ghost[2] * ghost[3]])
        prepared = tracks.prepare([list(ghost)], [0.8 * ghost[2] * ghost[3]], rows, [True])
        (view,) = tracks.update(prepared, [[0.01, 0.01, 0.01, 0.01, 0.96]])  # it even looks like a car
        assert view.track_id is None and not view.target and view.reason == STILL_REASON
    assert tracks.tracks == [] and tracks.ended == []


def test_still_regions_are_those_whose_pixels_did_not_change():
    still = StillRegions()
    mask = np.zeros((60, 80), np.uint8)
    mask[10:30, 10:30] = 255  # a ghost: foreground, but the same pixels frame after frame
    mask[10:30, 50:70] = 255  # a body moving 3 px a frame
    frame = np.full((60, 80), 100, np.uint8)
    boxes = [[10, 10, 20, 20], [50, 10, 20, 20]]
    assert still.flags(mask, boxes) == [False, False]  # no frame before: nothing is still
    for k in range(3):
        moved = frame.copy()
        moved[12:28, 50 + 3 * k: 62 + 3 * k] = 200
        still.next_frame(moved)
        if k:
            assert still.flags(mask, boxes) == [True, False]
        still.next_frame(moved)  # the same frame again (a repeated frame): no new frame
        if k:
            assert still.flags(mask, boxes) == [True, False]
    with pytest.raises(ValueError, match="max_still_share"):
        StillRegions(max_still_share=0.0)


def test_footprint_joiner_keeps_the_lists_when_nothing_joins():
    camera = steep_camera()
    joiner = FootprintJoiner(camera, RegionGeometry(camera), FootprintParams())
    boxes = [car_box_px(camera, 6.0, -4.0), car_box_px(camera, 6.0, 4.0)]
    areas = [100.0, 100.0]
    rows = joiner.geometry.rows(boxes, areas)
    assert joiner.join(boxes, areas, rows) == (boxes, areas, rows)
    with pytest.raises(ValueError, match="roof_m"):
        FootprintParams(roof_m=0.0)


def test_ghost_of_a_car_that_left_is_on_no_track_while_a_moving_car_is_tracked():
    """Through the whole detector: a car in the first frames (MOG2 learns it as background) leaves
    at once; the ground it uncovered is foreground for seconds but moves not, so it gets no track
    and never a target; a car driving past meanwhile gets one track."""
    from detector.detector import Detector
    from detector.general_model import default_model

    camera = steep_camera()
    detector = Detector(camera, model=default_model())
    rng = np.random.default_rng(0)
    ground = np.clip(rng.normal(100, 12, (camera.height_px, camera.width_px)), 0, 255).astype(np.uint8)
    parked = car_box_px(camera, 7.0, 2.5)
    seen = []
    for k in range(80):
        frame = ground.copy()
        if k < 40:  # parked (darker than the asphalt: what it uncovers is no shadow), then gone
            x, y, w, h = parked
            frame[y: y + h, x: x + w] = 30
        if k >= 30:  # a car driving in from the bottom of the view, away from the camera at 3 m/s
            x, y, w, h = car_box_px(camera, 3.0 + 0.25 * (k - 30), -2.0)
            frame[max(y, 0): y + h, x: x + w] = 200
        noise = rng.normal(0, 1.0, frame.shape)  # the sensor's, frame by frame
        frame = np.clip(frame + noise, 0, 255).astype(np.uint8)
        seen += [(k, d) for d in detector.process(frame)]
    x0, y0, w0, h0 = parked

    def on_ghost(d):
        x, y, w, h = d.box_px
        return x < x0 + w0 and x0 < x + w and y < y0 + h0 and y0 < y + h and x > camera.width_px / 2

    # from the frame after the car left (in that frame the car's pixels did change)
    ghosts = [d for k, d in seen if k > 40 and on_ghost(d)]
    assert len(ghosts) >= 5  # the ghost is there, frame after frame (8 here)
    assert all(d.track_id is None and not d.track_target and d.track_reason == STILL_REASON for d in ghosts)
    assert not any(d.track_target for _, d in seen if on_ghost(d))
    moving = [d.track_id for k, d in seen if not on_ghost(d) and d.track_id is not None]
    assert len(moving) >= 20 and len(set(moving)) == 1
