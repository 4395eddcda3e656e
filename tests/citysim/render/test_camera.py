"""The renderer draws what the camera model says, reports what it drew, and is reproducible."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from citysim.config.scenario import EnvironmentSpec
from citysim.render.blur import _smear
from citysim.render.camera import CameraRenderer, RenderOptions
from citysim.render.models import agent_shape
from citysim.world.agents import AgentState, MemberState
from citysim.world.street import LampSite, Lane, Sidewalk, StaticObject, Street
from detector.camera import CameraModel
from experiments.bench.scene import bench_render

PINHOLE = CameraModel(
    height_m=4.0,
    tilt_deg=20.0,
    focal_mm=0.73,
    sensor_w_mm=0.7,
    sensor_h_mm=0.52,
    width_px=320,
    height_px=240,
)
BARREL = PINHOLE.placed(k1=-0.25, k2=0.06, p1=0.002)
CAM_X, CAM_Y = 0.0, 6.0
_OPTION_FIELDS = ("ir_emitter_power", "motion_blur", "lamp_light", "branch_sway")


def settings(**kw) -> tuple[EnvironmentSpec, RenderOptions]:
    """A night (EnvironmentSpec) and the renderer's own switches (RenderOptions) from one set of
    keywords: ``ambient_light`` 1 is a day, ``distortion`` the lens, ``rain_drops_per_frame`` > 0
    a rainy night; the wind blows 3 m/s unless given."""
    kw = dict(kw)
    options = RenderOptions(**{k: kw.pop(k) for k in _OPTION_FIELDS if k in kw})
    if kw.pop("ambient_light", 0.0) == 1.0:
        kw["time_of_day"] = "day"
    if "distortion" in kw:
        kw["lens_distortion"] = kw.pop("distortion")
    if kw.get("rain_drops_per_frame", 0) > 0:
        kw["weather"] = "rain"
    kw.setdefault("wind_mps", 3.0)
    return EnvironmentSpec(**kw), options


#: noise, blur, distortion and sway off: every pixel is a pure function of the scene
EXACT_KW = dict(sensor_noise_std_dn=0.0, motion_blur=False, distortion=False, branch_sway=False)
EXACT = settings(**EXACT_KW)


def make_street(camera: CameraModel = PINHOLE, scenery: tuple[StaticObject, ...] = ()) -> Street:
    cam = camera.placed(x_m=CAM_X, y_m=CAM_Y, yaw_deg=0.0)
    lamps = (
        LampSite(0, CAM_X, CAM_Y, 6.0, cam, -12.5, 12.5),
        LampSite(1, 25.0, 6.8, 6.0, camera.placed(x_m=25.0, y_m=6.8, yaw_deg=180.0), 12.5, 37.5),
    )
    return Street(
        60.0,
        (Lane(-1.75, 3.5, -1), Lane(1.75, 3.5, 1)),
        (Sidewalk(-5.0, 3.0), Sidewalk(5.0, 3.0)),
        lamps,
        scenery,
    )


def renderer(
    params: tuple[EnvironmentSpec, RenderOptions] = EXACT, street: Street | None = None, seed: int = 0
) -> CameraRenderer:
    street = street or make_street()
    environment, options = params
    return CameraRenderer(street.lamps[0].camera, street, environment, np.random.default_rng(seed), options)


def walker(object_id: int, x: float, y: float, heading: float = math.pi / 2, **kw) -> AgentState:
    args = dict(speed_mps=1.4, length_m=0.6, width_m=0.5, height_m=1.75, gait_phase_rad=math.pi / 2)
    args.update(kw)
    return AgentState(object_id, "pedestrian", x, y, heading, **args)


def one_of_each(x: float) -> list[AgentState]:
    members = (
        MemberState(0.0, 0.45, 0.5, 1.75, 0.6, 0.0),
        MemberState(0.2, -0.45, 0.45, 1.6, 0.6, math.pi / 2),
    )
    return [
        walker(1, x, 4.5),
        AgentState(2, "group", x, 5.0, 0.0, 1.2, 0.8, 1.4, 1.75, members=members),
        AgentState(3, "cyclist", x, 2.5, 0.0, 5.0, 1.7, 0.6, 1.8, gait_phase_rad=1.0),
        AgentState(4, "vehicle", x, 1.75, math.pi, 12.0, 4.4, 1.8, 1.5),
        AgentState(5, "animal", x, 3.0, 0.5, 1.5, 0.8, 0.3, 0.5, gait_phase_rad=math.pi / 4),
    ]


def box_iou(a: tuple[int, int, int, int], b: tuple[int, int, int, int]) -> float:
    ax, ay, aw, ah = a
    bx, by, bw, bh = b
    iw = max(0, min(ax + aw, bx + bw) - max(ax, bx))
    ih = max(0, min(ay + ah, by + bh) - max(ay, by))
    inter = iw * ih
    return inter / (aw * ah + bw * bh - inter)


def changed_box(before: np.ndarray, after: np.ndarray) -> tuple[int, int, int, int]:
    return cv2.boundingRect((cv2.absdiff(before, after) > 0).astype(np.uint8))


# ------------------------------------------------------------------ reproducibility
def test_same_seed_same_frames_and_truth_bit_for_bit() -> None:
    street = make_street(BARREL, (StaticObject("tree", 15.0, 8.0, 3.0, 3.0, 6.0, 0.5),))
    params = settings(rain_drops_per_frame=40, insects_per_min=900.0, wind_mps=6.0)
    runs = []
    for _ in range(2):
        r = renderer(params, street, seed=42)
        frames = []
        for k in range(6):
            t = k / 15.0
            agents = [
                a if a.cls != "vehicle" else AgentState(**{**a.__dict__, "light_on": True})
                for a in one_of_each(12.0 + t)
            ]
            frames.append(r.render(t, agents, [1.0, 0.5 * k / 5]))
        runs.append(frames)
    for f1, f2 in zip(*runs, strict=True):
        assert np.array_equal(f1.image, f2.image)
        assert f1.truth == f2.truth
    other = renderer(params, street, seed=43).render(0.0, [], [1.0, 0.0])
    assert not np.array_equal(other.image, runs[0][0].image)


def test_indexed_frames_do_not_depend_on_the_frames_rendered_before() -> None:
    params = settings(rain_drops_per_frame=30, insects_per_min=1200.0)
    agents = one_of_each(14.0)
    in_order = renderer(params, seed=5)
    frames = [in_order.render(k / 15.0, agents, [1.0, 0.0], frame_index=k) for k in range(6)]
    alone = renderer(params, seed=5).render(5 / 15.0, agents, [1.0, 0.0], frame_index=5)
    assert np.array_equal(alone.image, frames[5].image) and alone.truth == frames[5].truth
    assert not np.array_equal(frames[4].image, frames[5].image)  # new noise every frame
    with pytest.raises(ValueError, match="frame_index"):
        in_order.render(0.0, [], [0.0, 0.0], frame_index=-1)


# ------------------------------------------------------------------ ground truth geometry
@pytest.mark.parametrize("index", range(5))
def test_truth_box_is_the_rendered_silhouette(index: int) -> None:
    agent = one_of_each(16.0)[index]
    r = renderer()
    empty = r.render(0.0, [], [0.0, 0.0]).image
    frame = r.render(0.0, [agent], [0.0, 0.0])
    (truth,) = frame.truth
    assert truth.object_id == agent.object_id and truth.cls == agent.cls
    drawn = changed_box(empty, frame.image)
    assert box_iou((truth.x, truth.y, truth.w, truth.h), drawn) >= 0.9
    assert not truth.touches_border and truth.fully_visible


@pytest.mark.parametrize("index", range(5))
def test_truth_box_matches_camera_projection_of_the_model(index: int) -> None:
    agent = one_of_each(14.0)[index]
    (truth,) = renderer().render(0.0, [agent], [0.0, 0.0]).truth
    uv = PINHOLE.placed(x_m=CAM_X, y_m=CAM_Y).project(
        agent_shape(agent).corners_m.reshape(-1, 3), distort=False
    )
    # pixels are filled where their centres fall inside the projected parts
    assert truth.x == pytest.approx(uv[:, 0].min(), abs=1.0)
    assert truth.x + truth.w - 1 == pytest.approx(uv[:, 0].max(), abs=1.0)
    assert truth.y == pytest.approx(uv[:, 1].min(), abs=1.0)
    assert truth.y + truth.h - 1 == pytest.approx(uv[:, 1].max(), abs=1.0)


def test_pedestrian_spans_the_rows_the_camera_model_gives() -> None:
    d_m, height_m = 11.0, 1.8
    agent = walker(1, d_m, CAM_Y, height_m=height_m, gait_phase_rad=0.0)
    (truth,) = renderer().render(0.0, [agent], [0.0, 0.0]).truth
    cam = PINHOLE.placed(x_m=CAM_X, y_m=CAM_Y)
    v_head, v_feet = cam.project(
        np.array([[d_m, CAM_Y, height_m], [d_m, CAM_Y, 0.0]]), distort=False
    )[:, 1]
    # feet reach half a leg depth nearer than the centre: allow for that at the bottom
    v_feet_near = cam.project(np.array([[d_m - 0.15, CAM_Y, 0.0]]), distort=False)[0, 1]
    assert truth.y == pytest.approx(v_head, abs=1.5)
    assert v_feet - 1.0 <= truth.y + truth.h - 1 <= v_feet_near + 1.0
    assert truth.distance_m == pytest.approx(d_m)
    assert truth.h == pytest.approx(v_feet - v_head, rel=0.08)


def test_distortion_moves_pixels_where_camera_project_says() -> None:
    street = make_street(BARREL)
    params = settings(
        sensor_noise_std_dn=0.0, motion_blur=False, distortion=True, branch_sway=False
    )
    cam = street.lamps[0].camera
    agent = walker(1, 9.0, CAM_Y + 3.2)  # well off the image centre, where the lens bends most
    (bent,) = renderer(params, street).render(0.0, [agent], [0.0, 0.0]).truth
    (straight,) = renderer(EXACT, street).render(0.0, [agent], [0.0, 0.0]).truth
    pts = agent_shape(agent).corners_m.reshape(-1, 3)
    for distort, truth in ((True, bent), (False, straight)):
        uv = cam.project(pts, distort=distort)
        assert truth.x == pytest.approx(uv[:, 0].min(), abs=1.5)
        assert truth.x + truth.w - 1 == pytest.approx(uv[:, 0].max(), abs=1.5)
        assert truth.y == pytest.approx(uv[:, 1].min(), abs=1.5)
        assert truth.y + truth.h - 1 == pytest.approx(uv[:, 1].max(), abs=1.5)
    assert abs(bent.x - straight.x) + abs(bent.y - straight.y) >= 4  # the lens did move it


def test_distorted_background_is_the_remapped_pinhole_background() -> None:
    street = make_street(BARREL)
    params = settings(
        sensor_noise_std_dn=0.0, motion_blur=False, distortion=True, branch_sway=False
    )
    bent = renderer(params, street).render(0.0, [], [1.0, 1.0]).image.astype(np.float32)
    straight = renderer(EXACT, street).render(0.0, [], [1.0, 1.0]).image.astype(np.float32)
    cam = street.lamps[0].camera
    rows, cols = np.mgrid[20:220:10, 20:300:10]
    ideal = cam.undistort_pixels(np.column_stack([cols.ravel(), rows.ravel()]).astype(np.float64))
    inside = (ideal[:, 0] >= 0) & (ideal[:, 0] <= 319) & (ideal[:, 1] >= 0) & (ideal[:, 1] <= 239)
    sampled = cv2.remap(
        straight,
        ideal[inside, 0].astype(np.float32).reshape(1, -1),
        ideal[inside, 1].astype(np.float32).reshape(1, -1),
        cv2.INTER_LINEAR,
    ).ravel()
    got = bent[rows.ravel()[inside], cols.ravel()[inside]]
    assert np.median(np.abs(got - sampled)) <= 2.0
    assert np.median(
        np.abs(got - straight[rows.ravel()[inside], cols.ravel()[inside]])
    ) > np.median(np.abs(got - sampled))


# ------------------------------------------------------------------ visibility flags
def test_agent_cut_by_the_frame_edge_touches_the_border() -> None:
    # the horizontal half field of view is atan(0.35 / 0.73): put the walker on that ray
    lateral_m = 10.0 * 0.35 / 0.73
    (truth,) = renderer().render(0.0, [walker(1, 10.0, CAM_Y + lateral_m)], [0.0, 0.0]).truth
    assert truth.x == 0 and truth.touches_border and not truth.fully_visible


def test_agent_mostly_behind_a_hedge_is_not_fully_visible() -> None:
    # the camera ray to a walker at (22, 2) crosses x = 16 at y = 3.09: a 2 m hedge there
    # hides everything below 1.25 m of a 1.75 m walker (71 %)
    hedge = StaticObject("hedge", 16.0, 3.09, 2.0, 2.0, 2.0, 0.35)
    r = renderer(street=make_street(scenery=(hedge,)))
    agent = walker(1, 22.0, 2.0)
    (truth,) = r.render(0.0, [agent], [0.0, 0.0]).truth
    assert not truth.fully_visible and not truth.touches_border
    (in_open,) = renderer().render(0.0, [agent], [0.0, 0.0]).truth
    assert truth.h < 0.5 * in_open.h
    assert truth.y == pytest.approx(in_open.y, abs=1)  # the head still shows
    taller = StaticObject("hedge", 16.0, 3.09, 2.0, 2.0, 3.0, 0.35)
    assert (
        renderer(street=make_street(scenery=(taller,))).render(0.0, [agent], [0.0, 0.0]).truth == ()
    )


def test_out_of_view_agents_have_no_truth() -> None:
    behind = walker(1, -10.0, CAM_Y)
    far_side = walker(2, 10.0, CAM_Y + 30.0)
    assert renderer().render(0.0, [behind, far_side], [0.0, 0.0]).truth == ()


# ------------------------------------------------------------------ light
def test_lamp_light_brightens_the_scene_around_its_pole() -> None:
    r = renderer()
    dark = r.render(0.0, [], [0.0, 0.0]).image.astype(float)
    lit = r.render(0.0, [], [0.0, 1.0]).image.astype(float)
    u, v = PINHOLE.placed(x_m=CAM_X, y_m=CAM_Y).project(
        np.array([[25.0, 5.0, 0.0]]), distort=False
    )[0]
    patch = (slice(int(v) - 3, int(v) + 4), slice(int(u) - 3, int(u) + 4))
    assert lit[patch].mean() > dark[patch].mean() + 20.0
    assert lit.mean() > dark.mean() + 5.0
    assert np.all(lit >= dark)
    half = r.render(0.0, [], [0.0, 0.5]).image.astype(float)
    assert dark[patch].mean() < half[patch].mean() < lit[patch].mean()
    off = (
        renderer(settings(**{**EXACT_KW, "lamp_light": False}))
        .render(0.0, [], [1.0, 1.0])
        .image
    )
    assert np.array_equal(off, dark.astype(np.uint8))


def test_lit_agents_throw_a_spot_ahead_and_lit_agents_are_brighter() -> None:
    r = renderer()
    car = AgentState(4, "vehicle", 9.0, -1.75, 0.0, 12.0, 4.4, 1.8, 1.5)
    dark = r.render(0.0, [car], [0.0, 0.0])
    lit = r.render(0.0, [AgentState(**{**car.__dict__, "light_on": True})], [0.0, 0.0])
    u, v = PINHOLE.placed(x_m=CAM_X, y_m=CAM_Y).project(
        np.array([[9.0 + 2.2 + 9.0, -1.75, 0.0]]), distort=False
    )[0]
    patch = (slice(int(v) - 2, int(v) + 3), slice(int(u) - 2, int(u) + 3))
    assert lit.image[patch].astype(float).mean() > dark.image[patch].astype(float).mean() + 15.0
    assert lit.truth == dark.truth  # light is not part of the silhouette
    # a walker under a lit lamp is brighter than in the dark
    w = walker(1, 24.0, 5.5)
    (t_dark,) = r.render(0.0, [w], [0.0, 0.0]).truth
    lit_lamp = r.render(0.0, [w], [0.0, 1.0]).image.astype(float)
    dark_lamp = r.render(0.0, [w], [0.0, 0.0]).image.astype(float)
    box = (slice(t_dark.y, t_dark.y + t_dark.h), slice(t_dark.x, t_dark.x + t_dark.w))
    assert lit_lamp[box].mean() > dark_lamp[box].mean() + 10.0


def test_day_light_removes_the_emitter_falloff() -> None:
    def near_far_ratio(params: tuple[EnvironmentSpec, RenderOptions]) -> float:
        img = renderer(params).render(0.0, [], [0.0, 0.0]).image.astype(float)
        cam = PINHOLE.placed(x_m=CAM_X, y_m=CAM_Y)
        (u_n, v_n), (u_f, v_f) = cam.project(
            np.array([[8.0, 4.0, 0.0], [35.0, 4.0, 0.0]]), distort=False
        )
        return img[int(v_n), int(u_n)] / max(img[int(v_f), int(u_f)], 1.0)

    assert near_far_ratio(EXACT) > 3.0
    assert near_far_ratio(settings(**{**EXACT_KW, "ambient_light": 1.0})) < 1.3


# ------------------------------------------------------------------ effects
def test_sensor_noise_has_the_requested_spread() -> None:
    std_dn = 4.0
    clean = renderer().render(0.0, [], [0.0, 0.0]).image.astype(float)
    noisy_r = renderer(settings(**{**EXACT_KW, "sensor_noise_std_dn": std_dn}), seed=3)
    a = noisy_r.render(0.0, [], [0.0, 0.0]).image.astype(float)
    b = noisy_r.render(1.0 / 15, [], [0.0, 0.0]).image.astype(float)
    mid = (clean > 20) & (clean < 230)  # away from clipping at 0 and 255
    assert np.std((a - clean)[mid]) == pytest.approx(std_dn, rel=0.15)
    assert abs(np.mean((a - clean)[mid])) < 0.3
    assert not np.array_equal(a, b)


def test_motion_blur_smears_along_the_image_motion() -> None:
    # a car crossing the view (heading +y) moves sideways in the image
    car = AgentState(4, "vehicle", 14.0, 4.0, math.pi / 2, 15.0, 4.4, 1.8, 1.5)
    blur_params = settings(**{**EXACT_KW, "motion_blur": True, "exposure_ms": 30.0})
    sharp_r, blur_r = renderer(), renderer(blur_params)
    empty = sharp_r.render(0.0, [], [0.0, 0.0]).image
    sharp = sharp_r.render(0.0, [car], [0.0, 0.0])
    blurred = blur_r.render(0.0, [car], [0.0, 0.0])
    cam = PINHOLE.placed(x_m=CAM_X, y_m=CAM_Y)
    smear_px = abs(
        np.diff(
            cam.project(np.array([[14.0, 4.0, 0.75], [14.0, 4.0 - 0.45, 0.75]]), distort=False)[
                :, 0
            ]
        )[0]
    )
    assert smear_px > 8.0
    w_sharp = changed_box(empty, sharp.image)[2]
    w_blur = changed_box(empty, blurred.image)[2]
    assert w_blur >= w_sharp + 0.7 * smear_px
    # truth is where the car covers more than half the exposure: its mid-exposure silhouette
    (ts,), (tb,) = sharp.truth, blurred.truth
    assert tb.w == pytest.approx(ts.w, abs=2)
    assert (tb.x + tb.w / 2) - (ts.x + ts.w / 2) == pytest.approx(smear_px / 2, abs=2.0)


@pytest.mark.parametrize("du_px, dv_px", [(3.0, 1.0), (20.0, 15.0), (-25.0, 9.0), (0.0, -30.0)])
def test_smear_keeps_the_light_and_moves_it_half_the_motion(du_px: float, dv_px: float) -> None:
    # long diagonal smears run at reduced resolution: they must still be the same smear
    layer = np.zeros((90, 120), np.float32)
    layer[30:50, 40:70] = 1.0
    out = _smear(layer, du_px, dv_px)
    assert out.sum() == pytest.approx(layer.sum(), rel=0.01)
    ys, xs = np.nonzero(out > 0.5)
    assert xs.mean() - 54.5 == pytest.approx(du_px / 2, abs=0.6)
    assert ys.mean() - 39.5 == pytest.approx(dv_px / 2, abs=0.6)
    spread = (
        np.nonzero(out.sum(axis=0) > 1e-3)[0]
        if abs(du_px) >= abs(dv_px)
        else np.nonzero(out.sum(axis=1) > 1e-3)[0]
    )
    assert np.ptp(spread) + 1 >= (30 if abs(du_px) >= abs(dv_px) else 20) + 0.8 * max(
        abs(du_px), abs(dv_px)
    )


def test_insects_rain_and_swaying_crowns_change_pixels_but_not_truth() -> None:
    street = make_street(scenery=(StaticObject("tree", 12.0, 8.5, 3.0, 3.0, 6.0, 0.5),))
    still = renderer(street=street)
    base = still.render(0.0, [], [0.0, 0.0]).image
    assert np.array_equal(base, still.render(0.7, [], [0.0, 0.0]).image)  # no sway: a static view

    bugs = renderer(settings(**{**EXACT_KW, "insects_per_min": 6000.0}), street)
    frames = [bugs.render(k / 15.0, [], [0.0, 0.0]) for k in range(5)]
    assert all(f.truth == () for f in frames)
    assert (
        max(int(cv2.absdiff(f.image, base).max()) for f in frames) > 60
    )  # bright blobs near the lens

    rain = renderer(settings(**{**EXACT_KW, "rain_drops_per_frame": 200}), street).render(
        0.0, [], [0.0, 0.0]
    )
    assert rain.truth == () and np.count_nonzero(cv2.absdiff(rain.image, base) > 3) > 500

    sway = renderer(
        settings(**{**EXACT_KW, "branch_sway": True, "wind_mps": 8.0}), street
    )
    frames = [sway.render(k / 5.0, [], [0.0, 0.0]).image for k in range(10)]  # two seconds
    moved = np.any([cv2.absdiff(frames[0], f) > 2 for f in frames[1:]], axis=0)
    assert np.count_nonzero(moved) > 20
    cam = street.lamps[0].camera
    uc, vc = cam.project(np.array([[12.0, 8.5, 4.0]]), distort=False)[0]
    ys, xs = np.nonzero(moved)
    assert np.median(np.hypot(xs - uc, ys - vc)) < 60  # the change is at the crown


# ------------------------------------------------------------------ input errors
def test_bad_inputs_raise_errors_that_name_the_field() -> None:
    with pytest.raises(ValueError, match="wind_mps"):
        EnvironmentSpec(wind_mps=-2.0)
    with pytest.raises(ValueError, match="motion_blur"):
        RenderOptions(motion_blur="yes")  # type: ignore[arg-type]
    r = renderer()
    with pytest.raises(ValueError, match="lamp_levels"):
        r.render(0.0, [], [1.0])
    for x_m in (10.0, -50.0):  # in view or behind the camera: a bad class is an error either way
        with pytest.raises(ValueError, match="'dragon'"):
            r.render(0.0, [AgentState(9, "dragon", x_m, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0)], [0.0, 0.0])
    with pytest.raises(ValueError, match=r"street\.scenery\[0\]\.kind"):
        renderer(
            street=make_street(scenery=(StaticObject("castle", 10.0, 9.0, 5.0, 5.0, 5.0, 0.3),))
        )


def test_bench_reports_ms_per_frame_for_each_object_count() -> None:
    got = bench_render((0, 3), frames=2)
    assert set(got) == {0, 3} and all(0.0 < ms < 1000.0 for ms in got.values())


# ------------------------------------------------------------------ batched drawing parts
@pytest.mark.parametrize("index", range(5))
def test_part_outlines_from_face_tables_fill_like_the_convex_hull(index: int) -> None:
    from citysim.render.models import draw_models
    from citysim.render.outline import outline_mask_bits, outline_tables

    model = draw_models([one_of_each(0.0)[index]])[0]
    k = 8
    rng = np.random.default_rng(index)
    for _ in range(6):
        # a random view: the model 6-15 m in front of a pinhole, turned any way
        yaw, pitch = rng.uniform(-math.pi, math.pi), rng.uniform(-1.2, 0.3)
        cy, sy, cp, sp = math.cos(yaw), math.sin(yaw), math.cos(pitch), math.sin(pitch)
        rot = np.array([[cy, -sy, 0.0], [sy * sp, cy * sp, -cp], [sy * cp, cy * cp, sp]])
        shift = np.array([rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(6, 15)])
        geo = model.geometry @ rot.T
        pts = geo[:, :k] + shift
        uv = 300.0 * pts[..., :2] / pts[..., 2:] + 200.0
        fixed = np.rint(uv * 16).astype(np.int32)
        front = np.einsum("pfk,k->pf", geo[:, k + 1 :], shift) < -model.faces[:, 1:]
        rows = model.faces[:, 0].astype(int)
        assert np.all(rows >= 0)  # every part of the detector's models has a table
        which = outline_tables()[rows, front @ outline_mask_bits()]
        assert np.all(which[:, 0] >= 0)
        for p in range(len(fixed)):
            by_table = np.zeros((400, 400), np.uint8)
            by_hull = np.zeros((400, 400), np.uint8)
            cv2.fillConvexPoly(by_table, fixed[p][which[p]], 1, cv2.LINE_8, 4)
            cv2.fillConvexPoly(by_hull, cv2.convexHull(fixed[p]), 1, cv2.LINE_8, 4)
            # the same polygon up to vertices a rounding off its hull edges
            assert np.count_nonzero(by_table != by_hull) <= 2 + 0.02 * by_hull.sum()


def test_box_minimum_is_a_lower_bound_and_exact_on_whole_cells() -> None:
    from citysim.render.canvas import RANGE_MIN_CELL_PX, BoxMinimum

    rng = np.random.default_rng(0)
    img = rng.uniform(0.0, 100.0, (70, 90)).astype(np.float32)
    low = BoxMinimum(img)
    boxes = []
    for _ in range(300):
        x0, y0 = rng.integers(0, 89), rng.integers(0, 69)
        boxes.append((x0, y0, rng.integers(x0 + 1, 91), rng.integers(y0 + 1, 71)))
    got = low.of(np.array(boxes))
    assert all(g <= img[y0:y1, x0:x1].min() for g, (x0, y0, x1, y1) in zip(got, boxes, strict=True))
    c = RANGE_MIN_CELL_PX
    assert low.of(np.array([(c, 2 * c, 5 * c, 4 * c)]))[0] == img[2 * c : 4 * c, c : 5 * c].min()


def test_frame_from_changed_boxes_is_the_whole_frame_converted() -> None:
    from citysim.render.output import FrameOutput, merge_boxes

    street = make_street(BARREL)
    params = settings(sensor_noise_std_dn=0.0, branch_sway=False)
    r = renderer(params, street)
    r.render(0.0, [], [1.0, 1.0])  # the still view is cached
    out: FrameOutput = r.output
    rng = np.random.default_rng(1)
    boxes = [(10, 20, 60, 90), (50, 80, 140, 120), (300, 10, 330, 40), (0, 200, 40, 260)]
    for x0, y0, x1, y1 in boxes:
        out.work[y0:y1, x0:x1] += rng.uniform(0.0, 0.5, (y1 - y0, x1 - x0)).astype(np.float32)
    expected = r.canvas.to_frame(light_to_dn(out.work.copy()))
    frame = out.finish(boxes)
    assert np.array_equal(frame, expected)
    assert np.array_equal(out.work, out.still)  # the still view is back for the next frame
    merged = merge_boxes(boxes + [(0, 0, 0, 5)])
    for x0, y0, x1, y1 in boxes:  # every box lies in a merged one; the empty box is dropped
        assert any(a <= x0 and b <= y0 and x1 <= c and y1 <= d for a, b, c, d in merged)


def light_to_dn(radiance: np.ndarray) -> np.ndarray:
    from citysim.render.light import radiance_to_dn

    return radiance_to_dn(radiance)


def test_agents_moving_alike_share_one_smear_and_keep_their_own_truth(monkeypatch) -> None:
    import citysim.render.agents as render_agents

    calls = []
    original = render_agents.composite

    def counting(*args, **kwargs):
        calls.append(args[1].members)
        return original(*args, **kwargs)

    monkeypatch.setattr(render_agents, "composite", counting)
    blur = settings(**{**EXACT_KW, "motion_blur": True})
    riders = [
        AgentState(1, "cyclist", 11.0, 4.0, math.pi / 2, 6.0, 1.7, 0.6, 1.8, gait_phase_rad=1.0),
        AgentState(2, "cyclist", 11.5, 4.8, math.pi / 2, 6.0, 1.7, 0.6, 1.8, gait_phase_rad=2.0),
    ]
    together = renderer(blur).render(0.0, riders, [0.0, 0.0]).truth
    assert len(calls) == 1 and sorted(calls[0]) == [0, 1]  # one smear for both
    alone = [renderer(blur).render(0.0, [a], [0.0, 0.0]).truth[0] for a in riders]
    for t in together:
        (a,) = [s for s in alone if s.object_id == t.object_id]
        assert box_iou((t.x, t.y, t.w, t.h), (a.x, a.y, a.w, a.h)) >= 0.6


def test_ground_spots_touch_only_the_boxes_they_return() -> None:
    from citysim.render.spots import add_ground_spots

    r = renderer()
    car = AgentState(4, "vehicle", 9.0, -1.75, 0.0, 12.0, 4.4, 1.8, 1.5, light_on=True)
    img = np.zeros(r.canvas.shape, np.float32)
    boxes = add_ground_spots(r.scene, img, [car], 1.0)
    assert boxes and img.max() > 0.1
    inside = np.zeros(img.shape, bool)
    for x0, y0, x1, y1 in boxes:
        inside[y0:y1, x0:x1] = True
    assert not np.any(img[~inside])
    assert inside.sum() < 0.6 * inside.size


def test_noise_fields_per_frame_index_are_fixed_and_varied() -> None:
    from citysim.render.effects.noise import SensorNoise

    picks = {SensorNoise.pick_for(7, k) for k in range(200)}
    assert len(picks) > 190  # hardly any repeats
    assert SensorNoise.pick_for(7, 3) == SensorNoise.pick_for(7, 3)
    assert SensorNoise.pick_for(7, 3) != SensorNoise.pick_for(8, 3)


def test_swaying_crowns_do_not_depend_on_the_frames_rendered_before() -> None:
    # two overlapping crowns: their poses are kept in the cached still view between frames
    trees = (
        StaticObject("tree", 12.0, 8.5, 3.0, 3.0, 6.0, 0.5),
        StaticObject("tree", 13.5, 8.0, 3.0, 3.0, 5.0, 0.5),
    )
    street = make_street(scenery=trees)
    params = settings(**{**EXACT_KW, "branch_sway": True, "wind_mps": 8.0})
    times = [k / 5.0 for k in range(8)]
    forward = renderer(params, street)
    ahead = [forward.render(t, [], [1.0, 0.0]).image for t in times]
    backward = renderer(params, street)
    behind = [backward.render(t, [], [1.0, 0.0]).image for t in reversed(times)][::-1]
    assert all(np.array_equal(a, b) for a, b in zip(ahead, behind, strict=True))
    assert not np.array_equal(ahead[0], ahead[3])  # the crowns did move
    relit = backward.render(times[2], [], [0.0, 0.0]).image  # lamp change: view rebuilt
    again = renderer(params, street).render(times[2], [], [0.0, 0.0]).image
    assert np.array_equal(relit, again)


def test_frames_under_changing_lamp_levels_do_not_depend_on_the_frames_rendered_before() -> None:
    # crowns lit by the lamps (their lit poses are kept while the levels stay) and boxes on a
    # distorted canvas (their frame boxes are kept): a fresh renderer must draw the same frame
    trees = (StaticObject("tree", 9.0, 7.5, 3.0, 3.0, 6.0, 0.5), StaticObject("tree", 20.0, 8.0, 3.0, 3.0, 5.0, 0.5))
    street = make_street(BARREL, scenery=trees)
    params = settings(**{**EXACT_KW, "branch_sway": True, "wind_mps": 8.0, "distortion": True})
    levels = [[1.0, 0.2], [0.5, 0.2], [1.0, 0.2], [1.0, 0.2], [0.2, 1.0], [1.0, 0.2]] * 2
    agents = one_of_each(14.0)
    sequence = renderer(params, street)
    frames = [sequence.render(k / 5.0, agents, lv, frame_index=k) for k, lv in enumerate(levels)]
    for k, lv in enumerate(levels):
        alone = renderer(params, street).render(k / 5.0, agents, lv, frame_index=k)
        assert np.array_equal(alone.image, frames[k].image) and alone.truth == frames[k].truth
    assert not np.array_equal(frames[0].image, frames[1].image)
