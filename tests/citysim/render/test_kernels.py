"""The renderer's compiled loops agree with plain references: exact geometry, OpenCV, numpy."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from citysim.render.agents import AgentLighting, part_radiance
from citysim.render.beams import BEAMS
from citysim.render.canvas import Z_NEAR_M
from citysim.render.kernels import SUBPIXEL_BITS, fill_ranks, label_stats
from citysim.render.models import agent_shape
from citysim.render.spots import add_ground_spots, spot_class
from citysim.world.agents import AgentState
from tests.citysim.render.test_camera import (
    BARREL,
    EXACT,
    EXACT_KW,
    PINHOLE,
    changed_box,
    make_street,
    one_of_each,
    renderer,
    settings,
)

ONE = 1 << SUBPIXEL_BITS


def centre_inside(poly_fixed: np.ndarray, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Exact integer test of every pixel centre against a convex polygon (either winding):
    (inside or on an edge, exactly on an edge)."""
    ys, xs = np.mgrid[0 : shape[0], 0 : shape[1]]
    px, py = xs * ONE, ys * ONE
    a = poly_fixed.astype(np.int64)
    b = np.roll(a, -1, axis=0)
    cross = np.stack(
        [
            (bx - ax) * (py - ay) - (by - ay) * (px - ax)
            for (ax, ay), (bx, by) in zip(a, b, strict=True)
        ]
    )
    inside = np.all(cross >= 0, axis=0) | np.all(cross <= 0, axis=0)
    return inside, np.any(cross == 0, axis=0)


@pytest.mark.parametrize("seed", range(8))
def test_parts_fill_the_pixels_whose_centres_they_hold(seed: int) -> None:
    rng = np.random.default_rng(seed)
    shape = (60, 80)
    polys, agent_parts, rois = [], [0], []
    for _agent in range(3):
        for _part in range(rng.integers(1, 4)):
            pts = rng.uniform([-5, -5], [85, 65], (rng.integers(3, 9), 2)) * ONE
            hull = cv2.convexHull(np.rint(pts).astype(np.int32))[:, 0]
            padded = np.concatenate([hull, np.repeat(hull[-1:], 8 - len(hull), 0)])[:8]
            polys.append(padded)
        agent_parts.append(len(polys))
        rois.append((0, 0, shape[1], shape[0]))
    ranks = np.zeros(shape, np.uint8)
    silhouettes = np.empty(3, np.int64)
    stacked = np.array(polys, np.int32)
    n_verts = np.full(len(polys), 8, np.int64)
    fill_ranks(ranks, stacked, n_verts, np.array(agent_parts), np.array(rois), silhouettes)
    expected = np.zeros(shape, np.uint8)
    on_edge = np.zeros(shape, bool)
    for p, poly in enumerate(polys):
        inside, edge = centre_inside(poly, shape)
        expected[inside] = p + 1
        on_edge |= edge
    clear = ~on_edge  # a centre exactly on an edge may go either way (floating point)
    assert np.array_equal(ranks[clear], expected[clear])
    # each agent's silhouette: its pixels before later (nearer) agents were drawn
    for a in range(3):
        mine = np.zeros(shape, bool)
        for p in range(agent_parts[a], agent_parts[a + 1]):
            mine |= centre_inside(polys[p], shape)[0]
        edge_px = int(np.count_nonzero(on_edge))
        assert abs(silhouettes[a] - np.count_nonzero(mine)) <= edge_px
    # OpenCV's own fill covers the same pixels but for its one-pixel outline
    cv_ranks = np.zeros(shape, np.uint8)
    for p, poly in enumerate(polys):
        cv2.fillConvexPoly(cv_ranks, poly, p + 1, cv2.LINE_8, SUBPIXEL_BITS)
    assert np.count_nonzero((ranks > 0) & (cv_ranks == 0)) == 0


def test_posed_parts_are_where_the_camera_model_projects_them() -> None:
    r = renderer(settings(**{**EXACT_KW, "motion_blur": True}))
    agents = one_of_each(12.0)
    lamps = np.array([[25.0, 6.8, 6.0]])
    lighting = AgentLighting.of(80.0, 0.0, lamps, np.array([0.7]))
    posed = r.painter.pose(agents, lighting)
    cam = r.canvas.camera
    for i, agent in enumerate(agents):
        shape = agent_shape(agent, quantise_phase=True)
        corners = shape.corners_m.reshape(-1, 3)
        s, e = posed.starts[i], posed.starts[i + 1]
        np.testing.assert_allclose(
            posed.cam_pts[s:e].reshape(-1, 3), cam.world_to_cam(corners), atol=1e-9
        )
        uv = cam.project(corners, distort=False).reshape(e - s, -1, 2)
        # each outline vertex is one of the part's projected vertices, rounded to 1/16 px
        for p in range(e - s):
            outline = posed.polys[s + p] / ONE
            gap = np.abs(outline[:, None, :] - uv[p][None, :, :]).max(axis=2).min(axis=1)
            assert gap.max() <= 0.5 / ONE + 1e-9
        centres = corners.reshape(e - s, -1, 3).mean(axis=1)
        expected = part_radiance(cam.world_to_cam(centres), centres, shape.ir_reflectance, lighting)
        np.testing.assert_allclose(posed.radiance[s:e], expected, rtol=1e-5)
        # distance of the body centre and image motion over the exposure
        mid = np.array([[agent.x_m, agent.y_m, 0.5 * agent.height_m]])
        assert posed.view[i, 0] == pytest.approx(np.linalg.norm(cam.world_to_cam(mid)), rel=1e-9)
        back_m = r.environment.exposure_ms / 1000.0 * agent.speed_mps
        before = mid - back_m * np.array(
            [[math.cos(agent.heading_rad), math.sin(agent.heading_rad), 0.0]]
        )
        motion = cam.project(before, distort=False) - cam.project(mid, distort=False)
        np.testing.assert_allclose(posed.view[i, 1:3], motion[0], atol=1e-6)


def test_label_statistics_match_a_remapped_label_image() -> None:
    r = renderer(settings(sensor_noise_std_dn=0.0), make_street(BARREL))
    canvas = r.canvas
    rng = np.random.default_rng(3)
    labels = np.zeros(canvas.shape, np.uint8)
    rois = []
    for label in range(1, 9):
        x0, y0 = rng.integers(0, canvas.width_px - 40), rng.integers(0, canvas.height_px - 40)
        w, h = rng.integers(3, 40, 2)
        cv2.ellipse(
            labels,
            (int(x0 + w // 2), int(y0 + h // 2)),
            (int(w // 2), int(h // 2)),
            0,
            0,
            360,
            label,
            -1,
        )
        rois.append((x0 - 2, y0 - 2, x0 + w + 2, y0 + h + 2))
    rois = np.clip(np.array(rois), 0, [canvas.width_px, canvas.height_px] * 2).astype(np.int64)
    stats = np.empty((8, 5), np.int64)
    label_stats(
        labels, *canvas.frame_uv, canvas.frame_to_canvas_index(), np.arange(1, 9), rois, stats
    )
    frame_labels = canvas.to_frame(labels, nearest=True)  # OpenCV's nearest remap
    for label in range(1, 9):
        x0, y0, x1, y1 = rois[label - 1]
        assert stats[label - 1, 0] == np.count_nonzero(labels[y0:y1, x0:x1] == label)
        seen = (frame_labels == label).astype(np.uint8)
        bx, by, bw, bh = cv2.boundingRect(seen)
        got = tuple(stats[label - 1, 1:])
        assert got == ((bx, by, bx + bw, by + bh) if bw else (0, 0, 0, 0))


def test_spots_follow_the_beam_formula_on_the_ground() -> None:
    r = renderer()
    car = AgentState(4, "vehicle", 6.0, -1.75, 0.1, 12.0, 4.4, 1.8, 1.5, light_on=True)
    img = np.zeros(r.canvas.shape, np.float32)
    add_ground_spots(r.scene, img, [car], 1.0)
    spec, row = BEAMS["headlights"], spot_class("vehicle").row
    f_frac, l_frac, f_far, half_w = row[:4]
    c, s = math.cos(car.heading_rad), math.sin(car.heading_rad)
    ox = car.x_m + c * f_frac * car.length_m - s * l_frac * car.width_m
    oy = car.y_m + s * f_frac * car.length_m + c * l_frac * car.width_m
    g = r.scene.ground_xy_m
    dx, dy = g[..., 0] - ox, g[..., 1] - oy
    f, lat = dx * c + dy * s, dy * c - dx * s
    width = spec.sigma_lateral_m + spec.spread_per_m * f
    e = (
        spec.peak_irradiance
        * np.exp(-(((f - spec.centre_m) / spec.sigma_forward_m) ** 2) - (lat / width) ** 2)
        * np.clip(f / 0.5, 0.0, 1.0)
    )
    e[~((f >= 0) & (f <= f_far) & (np.abs(lat) <= half_w))] = 0.0
    rho = r.scene.ground_reflectance
    bright = (e > 0.3 * spec.peak_irradiance) & (rho > 0)
    assert bright.sum() > 200
    # evaluated on cells 4 px apart and scaled up bilinearly: close everywhere, exact on average
    rel = img[bright] / rho[bright] / e[bright] - 1.0
    assert np.abs(rel).max() < 0.1 and abs(np.median(rel)) < 0.01
    # nothing lands behind the car's lamps or off the ground
    assert not np.any(img[(np.nan_to_num(f, nan=-1.0) < -0.5) | (rho == 0)])


def test_agent_straddling_the_near_plane_is_clipped_and_reported() -> None:
    r = renderer(EXACT, make_street(PINHOLE.placed(height_m=2.0, tilt_deg=5.0)))
    empty = r.render(0.0, [], [0.0, 0.0]).image
    # a car passing right beside a low camera: its rear is behind the camera's near plane
    car = AgentState(7, "vehicle", 1.5, 3.5, 0.0, 0.0, 4.4, 1.8, 1.5)
    lighting = AgentLighting.of(80.0, 0.0, np.zeros((0, 3)), np.zeros(0))
    assert r.painter.pose([car], lighting).agent_z[0, 0] < Z_NEAR_M
    frame = r.render(0.0, [car], [0.0, 0.0])
    (truth,) = frame.truth
    assert truth.touches_border and not truth.fully_visible
    assert np.count_nonzero(cv2.absdiff(empty, frame.image)) > 100
    assert (truth.x, truth.y, truth.w, truth.h) == changed_box(empty, frame.image)


def test_boxes_group_by_nearness_and_alike_motion() -> None:
    from citysim.render.kernels import group_boxes

    boxes = np.array([(10, 10, 30, 50), (25, 12, 45, 52), (28, 10, 48, 50), (200, 10, 220, 50)])
    motion = np.array([(4.0, 0.0), (4.3, 0.2), (-6.0, 0.0), (4.0, 0.0)])
    cluster_of, joint = np.empty(4, np.int64), np.empty((4, 6))
    k = group_boxes(boxes, motion, 1500, 1.0, 0.15, cluster_of, joint)
    # near and alike: together; near but moving the other way: apart; far away: apart
    assert k == 3 and cluster_of.tolist() == [0, 0, 1, 2]
    assert joint[0, :4].tolist() == [10, 10, 45, 52] and joint[0, 4:].tolist() == [8.3, 0.2]


def test_merged_boxes_cover_their_inputs_and_leave_nothing_worth_joining() -> None:
    from citysim.render.output import BOX_COST_PX, merge_boxes

    rng = np.random.default_rng(4)
    xy = rng.integers(0, 300, (25, 2))
    boxes = [(x, y, x + int(rng.integers(0, 60)), y + int(rng.integers(1, 60))) for x, y in xy]
    merged = merge_boxes(boxes)
    for x0, y0, x1, y1 in boxes:
        if x1 > x0:
            assert any(a <= x0 and b <= y0 and x1 <= c and y1 <= d for a, b, c, d in merged)
    for i, (a0, b0, a1, b1) in enumerate(merged):
        for c0, d0, c1, d1 in merged[i + 1 :]:
            joint = (max(a1, c1) - min(a0, c0)) * (max(b1, d1) - min(b0, d0))
            assert joint > (a1 - a0) * (b1 - b0) + (c1 - c0) * (d1 - d0) + BOX_COST_PX


def test_lamp_light_on_the_road_falls_as_the_cosine_of_the_angle_from_the_nadir() -> None:
    from citysim.render.light import LAMP_POWER, LAMP_SPREAD_DEG, lamp_irradiance

    h_m = 6.0
    x_m = np.array([0.0, 2.0, 5.0, 10.0, 20.0])
    road = np.column_stack([x_m, np.zeros(5), np.zeros(5)])
    up = np.tile([0.0, 0.0, 1.0], (5, 1))
    e = lamp_irradiance(road, up, np.array([[0.0, 0.0, h_m]]))[:, 0]
    cos_theta = h_m / np.hypot(h_m, x_m)
    # intensity P / cos^2 out to the spread angle: illuminance P cos(theta) / h^2 on the road
    inside = np.degrees(np.arccos(cos_theta)) <= LAMP_SPREAD_DEG
    np.testing.assert_allclose(e[inside], LAMP_POWER * cos_theta[inside] / h_m**2, rtol=1e-12)
    assert np.all(e[~inside] < LAMP_POWER * cos_theta[~inside] / h_m**2)  # beyond: cut off
    # a wall facing away from the lamp gets nothing
    away = lamp_irradiance(road[1:2], np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 0.0, h_m]]))
    assert away[0, 0] == 0.0
    # an upright body under the lamp: cosine 0.5 + half the lamp's elevation (1 overhead)
    body = lamp_irradiance(np.array([[0.0, 0.0, 1.0]]), None, np.array([[0.0, 0.0, h_m]]))
    assert body[0, 0] == pytest.approx(LAMP_POWER / (h_m - 1.0) ** 2)
