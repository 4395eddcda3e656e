"""Moving agents on the canvas: articulated shapes, IR shading, motion blur, occlusion.

Each ``AgentState`` becomes the detector's own 3D model (``citysim.render_models``,
the shapes the classifier is trained on), posed for all agents at once.
Agents are drawn far to near; each one on its own small layer (its bounding
box on the canvas):

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
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

from citysim import render_light as light
from citysim.agents import AgentState
from citysim.render_canvas import Z_NEAR_M, Canvas, clip_solid_near
from citysim.render_models import posed_models

SUBPIXEL_BITS = 4
#: Clothes, paint and fur face the camera at varied angles; one mean incidence cosine.
MEAN_INCIDENCE_COS = 0.8
#: Below this image motion over the exposure (px), blur is invisible and skipped.
MIN_BLUR_PX = 0.5


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
    cam_centres_m: np.ndarray,
    world_centres_m: np.ndarray,
    rho: np.ndarray,
    lighting: AgentLighting,
) -> np.ndarray:
    """Parts' radiance from their centres in the camera frame (N, 3; the emitter's view) and
    the world (N, 3; the lamps' view) and their reflectances (N,)."""
    r2 = np.einsum("ij,ij->i", cam_centres_m, cam_centres_m)
    cos_axis = np.maximum(cam_centres_m[:, 2], 0.0) / np.sqrt(np.maximum(r2, 1e-12))
    a = lighting.ambient_light
    emitter = (1.0 - a) * lighting.ir_emitter_power * MEAN_INCIDENCE_COS
    irr = emitter * cos_axis**light.BEAM_EXPONENT / np.maximum(r2, 0.04)
    irr += float(light.day_irradiance(a, 0.0)) + light.night_irradiance(a)
    if len(lighting.lamp_levels):
        irr += (
            light.lamp_irradiance(world_centres_m, None, lighting.lamp_positions_m)
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


#: Direct line filters are kept under this many taps; longer smears are done at lower resolution.
MAX_KERNEL_TAPS = 48


def _smear(layer: np.ndarray, du_px: float, dv_px: float) -> np.ndarray:
    """Motion blur of ``layer`` by the image motion (du, dv) px (see ``_blur_kernel``).

    A long diagonal smear would need a big 2-D kernel; the layer is then
    halved in resolution until the kernel is small, smeared, and scaled back.
    The smear is wider than the detail lost, so the result is indistinguishable.
    """
    level = 0
    while (abs(du_px) / 2**level + 2) * (abs(dv_px) / 2**level + 2) > MAX_KERNEL_TAPS:
        level += 1
    kernel, anchor = _blur_kernel(du_px / 2**level, dv_px / 2**level)
    if level == 0:
        return cv2.filter2D(layer, -1, kernel, anchor=anchor, borderType=cv2.BORDER_CONSTANT)
    h, w = layer.shape
    f = 2**level
    hs, ws = (h + f - 1) // f, (w + f - 1) // f
    # pad to whole f x f blocks so down- and up-scaling keep pixel centres aligned
    padded = cv2.copyMakeBorder(layer, 0, hs * f - h, 0, ws * f - w, cv2.BORDER_CONSTANT, value=0.0)
    small = cv2.resize(padded, (ws, hs), interpolation=cv2.INTER_AREA)
    small = cv2.filter2D(small, -1, kernel, anchor=anchor, borderType=cv2.BORDER_CONSTANT)
    return cv2.resize(small, (ws * f, hs * f), interpolation=cv2.INTER_LINEAR)[:h, :w]


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
        starts = np.zeros(len(agents) + 1, dtype=np.intp)
        np.cumsum(n_parts, out=starts[1:])
        owner = np.repeat(np.arange(len(agents)), n_parts)
        cam_pts = cam.world_to_cam(corners.reshape(-1, 3)).reshape(corners.shape)
        z = cam_pts[..., 2]
        # the common case - every vertex in front of the camera - is projected in one go;
        # agents wholly behind the camera are dropped, the few straddling it are clipped
        in_front = np.minimum.reduceat(z.min(axis=1), starts[:-1]) >= Z_NEAR_M
        behind = np.maximum.reduceat(z.max(axis=1), starts[:-1]) < Z_NEAR_M
        cam_centres = cam_pts.mean(axis=1)
        world_centres = corners.mean(axis=1) if len(lighting.lamp_levels) else None
        radiance = part_radiance(cam_centres, world_centres, rho, lighting).astype(np.float32)
        part_dist = np.sqrt(np.einsum("ij,ij->i", cam_centres, cam_centres))
        uv = self._to_canvas(cam_pts.reshape(-1, 3)).reshape(len(corners), -1, 2)
        fixed = np.rint(uv * (1 << SUBPIXEL_BITS)).astype(np.int32)
        lo = np.minimum.reduceat(uv.min(axis=1), starts[:-1])
        hi = np.maximum.reduceat(uv.max(axis=1), starts[:-1])
        order = np.lexsort((-part_dist, owner))  # grouped by agent, far parts first

        anchors = np.array([[a.x_m, a.y_m, 0.5 * a.height_m] for a in agents])
        agent_dist, motion = self._distance_and_motion(agents, anchors)
        drawn: list[DrawnAgent] = []
        number = np.arange(len(corners)) - starts[owner]  # each part's place within its agent
        dist_l, lo_l, hi_l, motion_l = (
            agent_dist.tolist(),
            lo.tolist(),
            hi.tolist(),
            motion.tolist(),
        )
        for i in np.argsort(-agent_dist, kind="stable").tolist():
            if behind[i]:
                continue
            parts = order[starts[i] : starts[i + 1]]
            if in_front[i]:
                polys = fixed[parts]
                box_lo, box_hi = lo_l[i], hi_l[i]
            else:
                polys, box_lo, box_hi = self._clipped_polygons(cam_pts[parts])
                if not polys:
                    continue
            result = self._paint_one(
                i,
                dist_l[i],
                motion_l[i],
                box_lo,
                box_hi,
                polys,
                number[parts],
                radiance[parts],
                img,
                occluder_depth,
                labels,
            )
            if result is not None:
                drawn.append(result)
        return drawn

    def _to_canvas(self, cam_pts: np.ndarray) -> np.ndarray:
        """Camera-frame points -> canvas coordinates; points before the near plane get
        meaningless (finite) coordinates - their agents are clipped or dropped instead."""
        cam = self.canvas.camera
        z = np.where(cam_pts[:, 2] >= Z_NEAR_M, cam_pts[:, 2], 1.0)
        u = cam.fx_px * cam_pts[:, 0] / z + (cam.cx_px - self.canvas.x0_px)
        v = cam.fy_px * cam_pts[:, 1] / z + (cam.cy_px - self.canvas.y0_px)
        return np.column_stack([u, v])

    def _distance_and_motion(
        self, agents: Sequence[AgentState], anchors_m: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Each agent's distance from the lens (m) and canvas displacement (N, 2) from time t
        back to t - exposure (0 without blur or when the agent is not in front)."""
        cam = self.canvas.camera
        n = len(agents)
        if not self.motion_blur:
            now = cam.world_to_cam(anchors_m)
            return np.sqrt(np.einsum("ij,ij->i", now, now)), np.zeros((n, 2))
        speed_heading = np.array([(a.speed_mps, a.heading_rad) for a in agents])
        back_m = self.exposure_s * speed_heading[:, 0]
        past = anchors_m.copy()
        past[:, 0] -= back_m * np.cos(speed_heading[:, 1])
        past[:, 1] -= back_m * np.sin(speed_heading[:, 1])
        both = cam.world_to_cam(np.concatenate([anchors_m, past]))
        dist = np.sqrt(np.einsum("ij,ij->i", both[:n], both[:n]))
        uv = self._to_canvas(both)
        ok = (both[:n, 2] >= Z_NEAR_M) & (both[n:, 2] >= Z_NEAR_M)
        return dist, np.where(ok[:, None], uv[n:] - uv[:n], 0.0)

    def _clipped_polygons(
        self, cam_pts: np.ndarray
    ) -> tuple[list[np.ndarray], list[float], list[float]]:
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
            return [], [0.0, 0.0], [0.0, 0.0]
        allpts = np.concatenate(pts)
        return polys, allpts.min(axis=0).tolist(), allpts.max(axis=0).tolist()

    def _paint_one(
        self,
        index: int,
        agent_dist_m: float,
        motion_px: Sequence[float],
        lo: Sequence[float],
        hi: Sequence[float],
        polys: Sequence[np.ndarray],
        part_numbers: np.ndarray,
        radiance: np.ndarray,
        img: np.ndarray,
        occluder_depth: np.ndarray,
        labels: np.ndarray,
    ) -> DrawnAgent | None:
        """Draw one agent whose parts ``polys`` (fixed-point canvas vertices) come far to near."""
        du, dv = motion_px
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
            value = _smear(value, du, dv)
            coverage = _smear(coverage, du, dv)
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
