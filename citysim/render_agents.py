"""Moving agents on the canvas: articulated shapes, IR shading, motion blur, occlusion.

Each ``AgentState`` becomes a ``detector.shapes.Shape`` through a registry
(the same 3D models the detector's classifier is trained on). Models are
built at the origin, cached (gait phase rounded to 1/32 of a cycle) and
placed at the agent's pose in one vectorised step for all agents. Agents are drawn
far to near; each one on its own small layer (its bounding box on the canvas):

1. every part's vertices are projected (clipped at the near plane when a part
   reaches behind the camera) and the convex hull filled with
   ``cv2.fillConvexPoly`` in 1/16-pixel fixed point, far parts first, writing
   the part's index; a lookup turns indices into radiance;
2. motion blur: the layer (radiance and coverage) is smeared along the
   agent's image motion over the exposure, from its image at time t back to
   its image at t - exposure (a line kernel, ``cv2.filter2D``);
3. pixels where a standing static surface (or a swaying crown) is nearer than
   the agent are cut away; the layer is composited over the frame and its
   covered pixels (coverage > 1/2) are labelled with the agent's number for the
   ground truth.

Part radiance is uniform per part: emitter light falling with the square of
the part's distance, daylight, and the lamps' light at the part (see
``citysim.render_light``).

Conventions: canvas pixels of ``citysim.render_canvas``; world frame of
DESIGN.md; ``heading_rad`` CCW from +x; radiance in linear full-scale units.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

from citysim import render_light as light
from citysim.agents import AgentState
from citysim.render_canvas import Z_NEAR_M, Canvas, clip_solid_near
from detector.shapes import (
    Shape,
    animal_shape,
    cyclist_shape,
    group_shape,
    pedestrian_shape,
    vehicle_shape,
)

SUBPIXEL_BITS = 4
#: Clothes, paint and fur face the camera at varied angles; one mean incidence cosine.
MEAN_INCIDENCE_COS = 0.8
#: Below this image motion over the exposure (px), blur is invisible and skipped.
MIN_BLUR_PX = 0.5


#: Gait phases are rounded to this many steps per cycle before a model is looked up in the
#: cache (0.2 rad: below what a 320x240 frame can show), so walkers reuse their models.
PHASE_STEPS = 32
_PHASE_STEP_RAD = 2.0 * math.pi / PHASE_STEPS


def quantised_phase(phase_rad: float) -> float:
    """The cached model's gait phase for ``phase_rad`` (nearest of PHASE_STEPS per cycle)."""
    return (round(phase_rad / _PHASE_STEP_RAD) % PHASE_STEPS) * _PHASE_STEP_RAD


def _exact(phase_rad: float) -> float:
    return phase_rad


PhaseMap = Callable[[float], float]


@dataclass(frozen=True)
class AgentModel:
    """How one class becomes a ``detector.shapes`` model: ``key`` names the model of an agent
    (everything but its pose; phases through the given map) and ``build`` makes it at the
    origin, heading +x."""

    key: Callable[[AgentState, PhaseMap], tuple]
    build: Callable[[tuple], Shape]


def _group_key(a: AgentState, phase: PhaseMap) -> tuple:
    if not a.members:
        raise ValueError(f"AgentState {a.object_id}: a 'group' needs members, got none")
    return (
        "group",
        tuple(
            (m.forward_m, m.left_m, m.width_m, m.height_m, m.length_m, phase(m.gait_phase_rad))
            for m in a.members
        ),
    )


#: AgentState.cls -> its 3D model (the detector's own shapes).
AGENT_MODELS: dict[str, AgentModel] = {
    "pedestrian": AgentModel(
        lambda a, phase: ("pedestrian", a.width_m, a.height_m, a.length_m, phase(a.gait_phase_rad)),
        lambda k: pedestrian_shape(0.0, 0.0, 0.0, *k[1:]),
    ),
    "group": AgentModel(_group_key, lambda k: group_shape(0.0, 0.0, 0.0, k[1])),
    "cyclist": AgentModel(
        lambda a, phase: ("cyclist", a.width_m, a.height_m, a.length_m, phase(a.gait_phase_rad)),
        lambda k: cyclist_shape(0.0, 0.0, 0.0, *k[1:]),
    ),
    "vehicle": AgentModel(
        lambda a, phase: ("vehicle", a.width_m, a.height_m, a.length_m),
        lambda k: vehicle_shape(0.0, 0.0, 0.0, *k[1:]),
    ),
    "animal": AgentModel(
        lambda a, phase: ("animal", a.width_m, a.height_m, a.length_m, phase(a.gait_phase_rad)),
        lambda k: animal_shape(0.0, 0.0, 0.0, *k[1:]),
    ),
}


def _model_of(agent: AgentState) -> AgentModel:
    model = AGENT_MODELS.get(agent.cls)
    if model is None:
        raise ValueError(
            f"AgentState {agent.object_id}: cls {agent.cls!r} cannot be rendered; valid: {sorted(AGENT_MODELS)}"
        )
    return model


@lru_cache(maxsize=8192)
def _model_at_origin(key: tuple) -> Shape:
    return AGENT_MODELS[key[0]].build(key)


def agent_shape(agent: AgentState, quantise_phase: bool = False) -> Shape:
    """The agent's 3D model at its pose (world frame). With ``quantise_phase`` the gait is the
    one the renderer draws (see PHASE_STEPS). ValueError naming the class if it is unknown."""
    key = _model_of(agent).key(agent, quantised_phase if quantise_phase else _exact)
    local = _model_at_origin(key) if quantise_phase else AGENT_MODELS[key[0]].build(key)
    return Shape(
        _place(local.corners_m, agent.x_m, agent.y_m, agent.heading_rad),
        local.ir_reflectance,
        local.part_kind,
    )


def _place(
    corners_m: np.ndarray,
    x_m: np.ndarray | float,
    y_m: np.ndarray | float,
    heading_rad: np.ndarray | float,
) -> np.ndarray:
    """Rotate local (P, K, 3) corners by heading about z and move them to (x, y); the pose
    arguments are scalars or (P,) per part."""
    c = np.reshape(np.cos(heading_rad), (-1, 1))
    s = np.reshape(np.sin(heading_rad), (-1, 1))
    out = np.empty_like(corners_m)
    out[..., 0] = np.reshape(x_m, (-1, 1)) + c * corners_m[..., 0] - s * corners_m[..., 1]
    out[..., 1] = np.reshape(y_m, (-1, 1)) + s * corners_m[..., 0] + c * corners_m[..., 1]
    out[..., 2] = corners_m[..., 2]
    return out


def posed_models(agents: Sequence[AgentState]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All agents' cached models placed at their poses in one go:
    (corners (sum P, K, 3) world, reflectances (sum P,), parts per agent (N,))."""
    locals_ = [_model_at_origin(_model_of(a).key(a, quantised_phase)) for a in agents]
    n_parts = np.array([m.n_parts for m in locals_])
    pose = np.array([[a.x_m, a.y_m, a.heading_rad] for a in agents])
    per_part = np.repeat(pose, n_parts, axis=0)
    corners = _place(
        np.concatenate([m.corners_m for m in locals_]),
        per_part[:, 0],
        per_part[:, 1],
        per_part[:, 2],
    )
    return corners, np.concatenate([m.ir_reflectance for m in locals_]), n_parts


@dataclass(frozen=True)
class DrawnAgent:
    """What one agent left on the canvas: its label, layer box and silhouette size (px)."""

    index: int  # position in the render call's agent sequence
    label: int  # value written into the label buffer
    roi: tuple[int, int, int, int]  # (x0, y0, x1, y1), exclusive ends, canvas
    silhouette_px: int  # pixels of its unoccluded silhouette at time t (blur excluded)


@dataclass(frozen=True)
class AgentLighting:
    """What lights the agents this frame."""

    ir_emitter_power: float
    ambient_light: float
    lamp_positions_m: np.ndarray  # (L, 3) only the lamps that are on
    lamp_levels: np.ndarray  # (L,)


def part_radiance(
    canvas: Canvas, centres_m: np.ndarray, rho: np.ndarray, lighting: AgentLighting
) -> np.ndarray:
    """(N, 3) part centres with reflectances -> (N,) radiance."""
    cam = canvas.camera
    rel = centres_m - cam.position_m
    r = np.linalg.norm(rel, axis=1)
    fwd = cam.rotation_world_to_cam[2]
    cos_axis = (rel @ fwd) / np.maximum(r, 1e-9)
    irr = light.emitter_irradiance(
        lighting.ir_emitter_power, lighting.ambient_light, r, MEAN_INCIDENCE_COS, cos_axis
    )
    irr = irr + light.day_irradiance(lighting.ambient_light, np.zeros(len(r)))
    irr = irr + light.night_irradiance(lighting.ambient_light)
    if len(lighting.lamp_levels):
        irr = (
            irr
            + light.lamp_irradiance(centres_m, None, lighting.lamp_positions_m)
            @ lighting.lamp_levels
        )
    return rho * irr


#: Blur kernels are cached on a grid of this many steps per pixel of motion.
KERNEL_STEPS_PER_PX = 4


def _blur_kernel(du_px: float, dv_px: float) -> tuple[np.ndarray, tuple[int, int]]:
    """Line kernel and its anchor for ``cv2.filter2D``: averages the layer over its positions
    from now (offset 0) back to ``(du, dv)`` px ago. The kernel only spans the line's bounding
    box, so a horizontal smear stays a cheap 1-3 row filter."""
    return _line_kernel(round(du_px * KERNEL_STEPS_PER_PX), round(dv_px * KERNEL_STEPS_PER_PX))


@lru_cache(maxsize=4096)
def _line_kernel(du_steps: int, dv_steps: int) -> tuple[np.ndarray, tuple[int, int]]:
    du_px, dv_px = du_steps / KERNEL_STEPS_PER_PX, dv_steps / KERNEL_STEPS_PER_PX
    # dst(p) = sum_o k(anchor + o) src(p + o): the layer seen s of the exposure ago sits at
    # +s*d, so pixel p sees the source at p - s*d: weight at offset o = -s*d (bilinear splat)
    n = int(math.ceil(2.0 * math.hypot(du_px, dv_px))) + 2
    s = np.linspace(0.0, 1.0, n)
    ox, oy = -s * du_px, -s * dv_px
    ax, ay = -math.floor(min(ox.min(), 0.0)), -math.floor(min(oy.min(), 0.0))
    width = ax + math.floor(max(ox.max(), 0.0)) + 2
    height = ay + math.floor(max(oy.max(), 0.0)) + 2
    x, y = ox + ax, oy + ay
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = x - x0, y - y0
    idx = np.concatenate(
        [y0 * width + x0, y0 * width + x0 + 1, (y0 + 1) * width + x0, (y0 + 1) * width + x0 + 1]
    )
    w = np.concatenate([(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy])
    kernel = np.bincount(idx, weights=w, minlength=width * height).reshape(height, width)
    kernel = (kernel / kernel.sum()).astype(np.float32)
    kernel.flags.writeable = False
    return kernel, (int(ax), int(ay))


class AgentPainter:
    """Draws agents on one camera's canvas (see the module docstring)."""

    def __init__(self, canvas: Canvas, exposure_ms: float, motion_blur: bool) -> None:
        self.canvas = canvas
        self.exposure_s = exposure_ms / 1000.0
        self.motion_blur = motion_blur and exposure_ms > 0.0
        # part indices of the agent being drawn; only its box is used and it is cleared after use
        self._index = np.zeros(canvas.shape, np.uint8)
        self._lut = np.zeros(256, np.float32)  # part number -> radiance, zero between uses

    def paint(
        self,
        agents: Sequence[AgentState],
        lighting: AgentLighting,
        img: np.ndarray,
        occluder_depth: np.ndarray,
        labels: np.ndarray,
    ) -> list[DrawnAgent]:
        """Composite ``agents`` into ``img`` (radiance) and ``labels``; far to near."""
        if not agents:
            return []
        cam = self.canvas.camera
        corners, rho, n_parts = posed_models(agents)  # (sum P, K, 3)
        starts = np.concatenate([[0], np.cumsum(n_parts)])
        owner = np.repeat(np.arange(len(agents)), n_parts)
        centres = corners.mean(axis=1)
        radiance = part_radiance(self.canvas, centres, rho, lighting).astype(np.float32)
        part_dist = np.linalg.norm(centres - cam.position_m, axis=1)
        cam_pts = cam.world_to_cam(corners.reshape(-1, 3)).reshape(corners.shape)
        # the common case - every vertex in front of the camera - is projected in one go;
        # agents wholly behind the camera are dropped, the few straddling it are clipped
        in_front = np.minimum.reduceat(cam_pts[..., 2].min(axis=1), starts[:-1]) >= Z_NEAR_M
        behind = np.maximum.reduceat(cam_pts[..., 2].max(axis=1), starts[:-1]) < Z_NEAR_M
        uv = self.canvas.cam_to_canvas(cam_pts.reshape(-1, 3)).reshape(len(corners), -1, 2)
        with np.errstate(invalid="ignore"):
            fixed = np.rint(np.clip(uv, -1e6, 1e6) * (1 << SUBPIXEL_BITS)).astype(np.int32)
        lo = np.minimum.reduceat(uv.min(axis=1), starts[:-1])
        hi = np.maximum.reduceat(uv.max(axis=1), starts[:-1])
        order = np.lexsort((-part_dist, owner))  # grouped by agent, far parts first

        anchors = np.array([[a.x_m, a.y_m, 0.5 * a.height_m] for a in agents])
        agent_dist = np.linalg.norm(anchors - cam.position_m, axis=1)
        motion = self._image_motion(agents, anchors)
        drawn: list[DrawnAgent] = []
        for i in np.argsort(-agent_dist, kind="stable"):
            if behind[i]:
                continue
            parts = order[starts[i] : starts[i + 1]]
            if in_front[i]:
                polys = [fixed[k] for k in parts]
                box_lo, box_hi = lo[i], hi[i]
            else:
                polys, box_lo, box_hi = self._clipped_polygons(cam_pts[parts])
                if not polys:
                    continue
            result = self._paint_one(
                int(i),
                float(agent_dist[i]),
                motion[i],
                box_lo,
                box_hi,
                polys,
                parts - starts[i],
                radiance[parts],
                img,
                occluder_depth,
                labels,
            )
            if result is not None:
                drawn.append(result)
        return drawn

    def _image_motion(self, agents: Sequence[AgentState], anchors_m: np.ndarray) -> np.ndarray:
        """(N, 2) canvas displacement of each agent from time t back to t - exposure (0 if no blur)."""
        motion = np.zeros((len(agents), 2))
        if not self.motion_blur:
            return motion
        speed = np.array([a.speed_mps for a in agents])
        heading = np.array([a.heading_rad for a in agents])
        back_m = self.exposure_s * speed
        past = anchors_m - np.column_stack(
            [back_m * np.cos(heading), back_m * np.sin(heading), np.zeros(len(agents))]
        )
        uv = self.canvas.project(np.concatenate([anchors_m, past]))
        d = uv[len(agents) :] - uv[: len(agents)]
        return np.where(np.isfinite(d), d, 0.0)

    def _clipped_polygons(
        self, cam_pts: np.ndarray
    ) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
        """Fixed-point canvas vertices of each part cut at the near plane (an empty array for a
        part wholly behind the camera), and the float bounds of what is left."""
        polys, pts = [], []
        for part in cam_pts:
            clipped = clip_solid_near(part)
            if clipped is None:
                polys.append(np.zeros((0, 2), np.int32))
                continue
            uv = self.canvas.cam_to_canvas(clipped)
            pts.append(uv)
            polys.append(np.rint(uv * (1 << SUBPIXEL_BITS)).astype(np.int32))
        if not pts:
            return [], np.zeros(2), np.zeros(2)
        allpts = np.concatenate(pts)
        return polys, allpts.min(axis=0), allpts.max(axis=0)

    def _paint_one(
        self,
        index: int,
        agent_dist_m: float,
        motion_px: np.ndarray,
        lo: np.ndarray,
        hi: np.ndarray,
        polys: list[np.ndarray],
        part_numbers: np.ndarray,
        radiance: np.ndarray,
        img: np.ndarray,
        occluder_depth: np.ndarray,
        labels: np.ndarray,
    ) -> DrawnAgent | None:
        """Draw one agent whose parts ``polys`` (fixed-point canvas vertices) come far to near."""
        du, dv = float(motion_px[0]), float(motion_px[1])
        blur = math.hypot(du, dv) >= MIN_BLUR_PX
        pad = int(math.ceil(max(abs(du), abs(dv)))) + 2 if blur else 1
        h, w = self.canvas.shape
        x0, y0 = max(math.floor(lo[0]) - pad, 0), max(math.floor(lo[1]) - pad, 0)
        x1, y1 = min(math.ceil(hi[0]) + pad + 1, w), min(math.ceil(hi[1]) + pad + 1, h)
        if x1 <= x0 or y1 <= y0:
            return None

        # fill parts far to near with their 1-based number: the nearest part wins each pixel;
        # the vertices lie in [x0, x1) x [y0, y1) or off the canvas, so only that box is touched
        parts_buf = self._index
        for poly, k in zip(polys, part_numbers.tolist(), strict=True):
            if len(poly):
                cv2.fillConvexPoly(
                    parts_buf, cv2.convexHull(poly), k + 1, cv2.LINE_8, SUBPIXEL_BITS
                )
        index_buf = self._index[y0:y1, x0:x1]
        silhouette_px = cv2.countNonZero(index_buf)
        if silhouette_px == 0:
            return None
        lut = self._lut
        lut[part_numbers + 1] = radiance
        value = cv2.LUT(index_buf, lut)  # premultiplied radiance
        lut[part_numbers + 1] = 0.0
        coverage = cv2.LUT(index_buf, _COVERAGE_LUT)
        index_buf.fill(0)
        if blur:
            kernel, anchor = _blur_kernel(du, dv)
            value = cv2.filter2D(value, -1, kernel, anchor=anchor, borderType=cv2.BORDER_CONSTANT)
            coverage = cv2.filter2D(
                coverage, -1, kernel, anchor=anchor, borderType=cv2.BORDER_CONSTANT
            )
        visible = cv2.compare(occluder_depth[y0:y1, x0:x1], agent_dist_m, cv2.CMP_GE)
        if cv2.countNonZero(visible) < visible.size:
            value = cv2.bitwise_and(value, value, mask=visible)
            coverage = cv2.bitwise_and(coverage, coverage, mask=visible)
        view = img[y0:y1, x0:x1]
        cv2.subtract(view, cv2.multiply(view, coverage), dst=view)
        cv2.add(view, value, dst=view)
        label = index + 1
        labels[y0:y1, x0:x1][coverage > 0.5] = label
        return DrawnAgent(index, label, (x0, y0, x1, y1), silhouette_px)


_COVERAGE_LUT = np.ones(256, np.float32)
_COVERAGE_LUT[0] = 0.0
