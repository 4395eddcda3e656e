"""Moving agents on the canvas: articulated shapes, IR shading, motion blur, occlusion.

Each ``AgentState`` becomes the detector's own 3D model (``citysim.render_models``,
the shapes the classifier is trained on). Python call overhead, not pixels,
is what agents cost, so everything that can is done for all agents of a
frame at once:

1. one rotation per agent takes every model's vertices, part centres and
   face normals to the camera frame; all vertices are projected together;
   each part's outline - its image's convex polygon - is read from the
   model's cached table by which faces look at the camera
   (``citysim.render_outline``), no hull per part and frame;
2. part radiance for all parts at once (emitter light falling with the
   square of the distance, daylight, the lamps' light at the part; see
   ``citysim.render_light``);
3. agents are drawn far to near into one buffer of part *ranks*
   (``cv2.fillConvexPoly`` in 1/16-pixel fixed point, far parts first, one
   rank per part, 255 parts per batch), so nearer parts win each pixel; each
   agent's silhouette is counted as it is drawn, before nearer ones cover it;
4. agents close together with alike image motion form a cluster, which is
   cut where standing surfaces are nearer, smeared, composited and labelled
   for the ground truth in one go (``citysim.render_clusters``).

Agents straddling the camera's near plane are clipped part by part (rare).

Conventions: canvas pixels of ``citysim.render_canvas``; world frame of
DESIGN.md; ``heading_rad`` CCW from +x; radiance in linear full-scale units.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from citysim import render_light as light
from citysim.agents import AgentState
from citysim.render_blur import MIN_BLUR_PX, _smear
from citysim.render_canvas import Z_NEAR_M, BoxMinimum, Canvas, clip_solid_near
from citysim.render_clusters import PaintFrame, clusters, composite
from citysim.render_models import draw_models
from citysim.render_outline import outline_mask_bits, outline_tables
from detector.shape_parts import VERTICES_PER_PART

SUBPIXEL_BITS = 4
#: Clothes, paint and fur face the camera at varied angles; one mean incidence cosine.
MEAN_INCIDENCE_COS = 0.8

__all__ = ["AgentLighting", "AgentPainter", "DrawnAgent", "part_radiance", "_smear"]


@dataclass(frozen=True)
class DrawnAgent:
    """What one agent left on the canvas: its label, layer box and silhouette size (px)."""

    index: int  # position in the render call's agent sequence
    label: int  # value written into the label buffer
    roi: tuple[int, int, int, int]  # (x0, y0, x1, y1), exclusive ends, canvas
    silhouette_px: int  # pixels of its unoccluded silhouette at time t (blur excluded)


@dataclass(frozen=True)
class AgentLighting:
    """What lights the agents this frame (``of`` fills in the derived fields)."""

    ir_emitter_power: float
    ambient_light: float
    lamp_positions_m: np.ndarray  # (L, 3) only the lamps that are on
    lamp_levels: np.ndarray  # (L,)
    emitter_gain: float = 0.0  # emitter irradiance x m^2 on a part facing it on the axis
    uniform_irradiance: float = 0.0  # daylight on upright surfaces + sky glow

    @classmethod
    def of(
        cls,
        ir_emitter_power: float,
        ambient_light: float,
        lamp_positions_m: np.ndarray,
        lamp_levels: np.ndarray,
    ) -> AgentLighting:
        a = ambient_light
        return cls(
            ir_emitter_power,
            a,
            lamp_positions_m,
            lamp_levels,
            (1.0 - a) * ir_emitter_power * MEAN_INCIDENCE_COS,
            float(light.day_irradiance(a, 0.0)) + light.night_irradiance(a),
        )


def part_radiance(
    cam_centres_m: np.ndarray,
    world_centres_m: np.ndarray | None,
    rho: np.ndarray,
    lighting: AgentLighting,
) -> np.ndarray:
    """Parts' radiance from their centres in the camera frame (N, 3; the emitter's view) and
    the world (N, 3; the lamps' view) and their reflectances (N,)."""
    r2 = np.einsum("ij,ij->i", cam_centres_m, cam_centres_m)
    cos_axis = np.maximum(cam_centres_m[:, 2], 0.0) / np.sqrt(np.maximum(r2, 1e-12))
    irr = lighting.emitter_gain * cos_axis**light.BEAM_EXPONENT / np.maximum(r2, 0.04)
    irr += lighting.uniform_irradiance
    if len(lighting.lamp_levels):
        irr += (
            light.lamp_irradiance(world_centres_m, None, lighting.lamp_positions_m)
            @ lighting.lamp_levels
        )
    return rho * irr


class AgentPainter:
    """Draws agents on one camera's canvas (see the module docstring)."""

    def __init__(self, canvas: Canvas, exposure_ms: float, motion_blur: bool) -> None:
        self.canvas = canvas
        self.exposure_s = exposure_ms / 1000.0
        self.motion_blur = motion_blur and exposure_ms > 0.0
        # part ranks of the batch being drawn (0 = no part); cleared box by box after use
        self._ranks = np.zeros(canvas.shape, np.uint8)
        cam = canvas.camera
        self._rot = cam.rotation_world_to_cam
        self._pole = cam.position_m
        self._focal = np.array([cam.fx_px, cam.fy_px])
        self._centre = np.array([cam.cx_px - canvas.x0_px, cam.cy_px - canvas.y0_px])

    def paint(
        self,
        agents: Sequence[AgentState],
        lighting: AgentLighting,
        img: np.ndarray,
        occluder_depth: np.ndarray,
        nearest_occluder: BoxMinimum,
        labels: np.ndarray,
    ) -> tuple[list[DrawnAgent], list[tuple[int, int, int, int]]]:
        """Composite ``agents`` into ``img`` (radiance) and ``labels``, far to near: what was
        drawn, and the canvas boxes drawn on.

        ``nearest_occluder`` bounds ``occluder_depth`` from below over boxes: agents with no
        nearer standing surface in their box skip the per-pixel occlusion test.
        """
        boxes: list[tuple[int, int, int, int]] = []
        if not agents:
            return [], boxes
        n = len(agents)
        models = draw_models(agents)
        n_parts = [m.n_parts for m in models]
        starts = [0, *itertools.accumulate(n_parts)]
        owner = np.repeat(np.arange(n), n_parts)
        pose = np.array([(a.x_m, a.y_m, a.heading_rad, a.height_m, a.speed_mps) for a in agents])
        cam = self.canvas.camera
        rot = self._rot
        # each agent's model frame -> camera frame: rotation to_cam (heading, then the
        # camera's rotation) and the model origin's camera-frame position shift
        c, s = np.cos(pose[:, 2]), np.sin(pose[:, 2])
        to_cam = np.empty((n, 3, 3))
        to_cam[:, :, 0] = c[:, None] * rot[:, 0] + s[:, None] * rot[:, 1]
        to_cam[:, :, 1] = c[:, None] * rot[:, 1] - s[:, None] * rot[:, 0]
        to_cam[:, :, 2] = rot[:, 2]
        shift = (pose[:, :2] - self._pole[:2]) @ rot[:, :2].T - self._pole[2] * rot[:, 2]
        geometry = np.matmul(
            np.concatenate([m.geometry for m in models]), to_cam[owner].transpose(0, 2, 1)
        )
        k = VERTICES_PER_PART
        part_shift = shift[owner]
        geometry[:, : k + 1] += part_shift[:, None, :]  # vertices and centre; not the normals
        cam_pts = geometry[:, :k]
        cam_centres = geometry[:, k]
        z_part = cam_pts[..., 2].min(axis=1)
        if z_part.min() >= Z_NEAR_M:  # the common case: every vertex in front of the camera
            straddle, behind = [], set()
        else:  # agents wholly behind the camera are dropped, the few straddling it clipped
            z_max = cam_pts[..., 2].max(axis=1)
            front = (np.minimum.reduceat(z_part, starts[:-1]) >= Z_NEAR_M).tolist()
            back = (np.maximum.reduceat(z_max, starts[:-1]) < Z_NEAR_M).tolist()
            behind = {i for i in range(n) if back[i]}
            straddle = [i for i in range(n) if not front[i] and not back[i]]
        world_centres = cam_centres @ rot + cam.position_m if len(lighting.lamp_levels) else None
        rho = np.concatenate([m.reflectance for m in models])
        radiance = part_radiance(cam_centres, world_centres, rho, lighting).astype(np.float32)
        part_dist = np.einsum("ij,ij->i", cam_centres, cam_centres)  # squared: for the order
        uv = self._to_canvas(cam_pts)
        flat_uv = uv.reshape(-1, 2)
        bounds = np.concatenate(
            [
                np.minimum.reduceat(flat_uv, np.multiply(starts[:-1], k)),
                np.maximum.reduceat(flat_uv, np.multiply(starts[:-1], k)),
            ],
            axis=1,
        ).tolist()
        order = np.lexsort((-part_dist, owner))  # grouped by agent, far parts first
        polys = self._outlines(
            np.rint(uv * (1 << SUBPIXEL_BITS)).astype(np.int32),
            part_shift,
            geometry[:, k + 1 :],
            np.concatenate([m.faces for m in models]),
        )[order]
        radiance = radiance[order]

        clipped: dict[int, list[np.ndarray]] = {}
        for i in straddle:
            parts, lo, hi = self._clipped_polygons(cam_pts[order[starts[i] : starts[i + 1]]])
            clipped[i] = parts
            bounds[i] = lo + hi
            if not parts:
                behind.add(i)

        # per agent, in plain Python (a few dozen agents: cheaper than array calls)
        h, w = self.canvas.shape
        fx, fy = self._focal.tolist()
        cx, cy = self._centre.tolist()
        up = rot[:, 2].tolist()
        back_m = (self.exposure_s * pose[:, 4]).tolist() if self.motion_blur else [0.0] * n
        rois, dist, motion, shown = [], [], [], []
        for i, (sx, sy, sz), (hx, hy, hz), half_h, back, (ux0, uy0, ux1, uy1) in zip(
            range(n),
            shift.tolist(),
            to_cam[:, :, 0].tolist(),
            (0.5 * pose[:, 3]).tolist(),
            back_m,
            bounds,
            strict=True,
        ):
            # the agent's centre now and an exposure ago (back along its heading, +x)
            nx, ny, nz = sx + half_h * up[0], sy + half_h * up[1], sz + half_h * up[2]
            dist.append(math.sqrt(nx * nx + ny * ny + nz * nz))
            px, py, pz = nx - back * hx, ny - back * hy, nz - back * hz
            du = dv = 0.0
            if back > 0.0 and nz >= Z_NEAR_M and pz >= Z_NEAR_M:
                du = fx * (px / pz - nx / nz)
                dv = fy * (py / pz - ny / nz)
            motion.append((du, dv))
            pad = math.ceil(max(abs(du), abs(dv))) + 2 if math.hypot(du, dv) >= MIN_BLUR_PX else 1
            x0 = min(max(math.floor(max(ux0, -1e6)) - pad, 0), w)
            y0 = min(max(math.floor(max(uy0, -1e6)) - pad, 0), h)
            x1 = max(min(math.ceil(min(ux1, 1e6)) + pad + 1, w), 0)
            y1 = max(min(math.ceil(min(uy1, 1e6)) + pad + 1, h), 0)
            rois.append((x0, y0, x1, y1))
            if x1 > x0 and y1 > y0 and i not in behind:
                shown.append(i)
        if not shown:
            return [], boxes
        cut = [False] * n
        nearest = nearest_occluder.of(np.array([rois[i] for i in shown])).tolist()
        for i, near_m in zip(shown, nearest, strict=True):
            cut[i] = near_m < dist[i]

        far_first = sorted(shown, key=lambda i: -dist[i])
        ctx = PaintFrame(rois, dist, motion, cut, img, occluder_depth, labels, boxes)
        drawn: list[DrawnAgent] = []
        batch: list[int] = []
        batch_parts = 0
        for i in far_first:
            if batch_parts + n_parts[i] > 255:
                drawn += self._draw_batch(batch, ctx, starts, polys, clipped, radiance)
                batch, batch_parts = [], 0
            batch.append(i)
            batch_parts += n_parts[i]
        drawn += self._draw_batch(batch, ctx, starts, polys, clipped, radiance)
        return drawn, boxes

    def _outlines(
        self,
        fixed: np.ndarray,
        part_shift: np.ndarray,
        normals: np.ndarray,
        faces: np.ndarray,
    ) -> np.ndarray:
        """Every part's outline: its fixed-point vertices (P, K, 2) reordered as its image's
        convex polygon (``citysim.render_outline``; the hull for parts without a table).
        ``part_shift`` (P, 3) is each part's model origin and ``normals`` (P, F, 3) its face
        normals in the camera frame; ``faces`` as ``DrawModel.faces``."""
        rows = faces[:, 0].astype(np.intp)
        # a face looks at the camera (the origin, at -shift in the rotated model frame) when
        # normal . (-shift) > offset
        front = np.einsum("pfk,pk->pf", normals, part_shift) < -faces[:, 1:]
        table = outline_tables()
        if not len(table):
            which = np.full(fixed.shape[:2], -1)
        else:
            which = table[np.maximum(rows, 0), front @ outline_mask_bits()]
        p = np.arange(len(fixed))[:, None]
        out = fixed[p, np.maximum(which, 0)]
        for j in np.flatnonzero((rows < 0) | (which[:, 0] < 0)).tolist():
            hull = cv2.convexHull(fixed[j])[:, 0]
            out[j] = np.concatenate([hull, np.repeat(hull[-1:], len(fixed[j]) - len(hull), 0)])
        return out

    def _to_canvas(self, cam_pts: np.ndarray) -> np.ndarray:
        """Camera-frame points (..., 3) -> canvas coordinates (..., 2); points before the near
        plane get meaningless (finite) coordinates - their agents are clipped or dropped."""
        z = np.maximum(cam_pts[..., 2:], Z_NEAR_M)
        return cam_pts[..., :2] / z * self._focal + self._centre

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

    def _draw_batch(
        self,
        batch: list[int],
        ctx: PaintFrame,
        starts: list[int],
        polys: np.ndarray,
        clipped: dict[int, list[np.ndarray]],
        radiance: np.ndarray,
    ) -> list[DrawnAgent]:
        """Fill the parts of ``batch`` (agents far to near) by rank, then composite them
        cluster by cluster (agents near each other with alike motion). ``polys`` and
        ``radiance`` are per part, each agent's parts together, far parts first."""
        if not batch:
            return []
        ranks = self._ranks
        lut = np.zeros(256, np.float32)  # rank -> radiance
        names = np.zeros(256, ctx.labels.dtype)  # rank -> label
        rank = 1
        first, end, silhouettes = {}, {}, {}
        fill = cv2.fillConvexPoly
        for i in batch:
            s, e = starts[i], starts[i + 1]
            first[i] = rank
            lut[rank : rank + e - s] = radiance[s:e]
            names[rank : rank + e - s] = i + 1
            if i in clipped:
                for j, poly in enumerate(clipped[i]):
                    if len(poly):
                        fill(ranks, cv2.convexHull(poly), rank + j, cv2.LINE_8, SUBPIXEL_BITS)
            else:
                for j in range(s, e):
                    fill(ranks, polys[j], rank + j - s, cv2.LINE_8, SUBPIXEL_BITS)
            rank += e - s
            end[i] = rank
            x0, y0, x1, y1 = ctx.rois[i]
            # counted now: nearer agents, drawn later, may cover it
            mine = cv2.compare(ranks[y0:y1, x0:x1], first[i] - 1, cv2.CMP_GT)
            silhouettes[i] = cv2.countNonZero(mine)
        drawn = []
        cluster_of = np.full(256, -1, np.intp)  # rank -> cluster
        groups = clusters([i for i in batch if silhouettes[i] > 0], ctx)
        for c, cluster in enumerate(groups):
            for i in cluster.members:
                cluster_of[first[i] : end[i]] = c
        for c, cluster in enumerate(groups):
            mine = (cluster_of == c).astype(np.float32)
            composite(
                self._ranks,
                cluster,
                ctx,
                lut * mine,
                names * mine.astype(names.dtype),
                mine,
                first,
                end,
            )
            ctx.boxes.append(tuple(cluster.box))
            drawn += [DrawnAgent(i, i + 1, ctx.rois[i], silhouettes[i]) for i in cluster.members]
        for i in batch:
            x0, y0, x1, y1 = ctx.rois[i]
            ranks[y0:y1, x0:x1] = 0
        return drawn
