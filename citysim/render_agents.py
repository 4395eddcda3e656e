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

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from citysim import render_light as light
from citysim.agents import AgentState
from citysim.render_blur import (
    MIN_BLUR_PX,
    _smear,
    similar_motion,
    smear_stacked,
    stacked_layers,
)
from citysim.render_canvas import Z_NEAR_M, BoxMinimum, Canvas, clip_solid_near
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
        n_parts_l = [m.n_parts for m in models]
        starts_l = [0, *itertools.accumulate(n_parts_l)]
        starts = np.array(starts_l)
        owner = np.repeat(np.arange(n), n_parts_l)
        pose = np.array(
            [(a.x_m, a.y_m, 0.0, a.heading_rad, a.height_m, a.speed_mps) for a in agents]
        )
        heading, height, speed = pose[:, 3], pose[:, 4], pose[:, 5]
        # one rotation per agent takes its model (vertices, centres, face normals) to the
        # camera frame
        c, s = np.cos(heading), np.sin(heading)
        turn = np.zeros((n, 3, 3))
        turn[:, 0, 0] = turn[:, 1, 1] = c
        turn[:, 0, 1], turn[:, 1, 0] = -s, s
        turn[:, 2, 2] = 1.0
        cam = self.canvas.camera
        rot = cam.rotation_world_to_cam
        to_cam = rot @ turn  # (n, 3, 3)
        shift = (pose[:, :3] - cam.position_m) @ rot.T  # each agent's origin, camera frame
        geometry = np.matmul(
            np.concatenate([m.geometry for m in models]), to_cam[owner].transpose(0, 2, 1)
        )
        k = VERTICES_PER_PART
        part_shift = shift[owner]
        cam_pts = geometry[:, :k] + part_shift[:, None, :]  # (sum P, K, 3)
        cam_centres = geometry[:, k] + part_shift
        z = cam_pts[..., 2]
        z_part = z.min(axis=1)
        if z_part.min() >= Z_NEAR_M:  # the common case: every vertex in front of the camera
            in_front = np.ones(n, dtype=bool)
            behind = ~in_front
        else:  # agents wholly behind the camera are dropped, the few straddling it clipped
            in_front = np.minimum.reduceat(z_part, starts[:-1]) >= Z_NEAR_M
            behind = np.maximum.reduceat(z.max(axis=1), starts[:-1]) < Z_NEAR_M
        world_centres = cam_centres @ rot + cam.position_m if len(lighting.lamp_levels) else None
        rho = np.concatenate([m.reflectance for m in models])
        radiance = part_radiance(cam_centres, world_centres, rho, lighting).astype(np.float32)
        part_dist = np.einsum("ij,ij->i", cam_centres, cam_centres)  # squared: for the order
        uv = self._to_canvas(cam_pts)
        flat_uv = uv.reshape(-1, 2)
        lo = np.minimum.reduceat(flat_uv, starts[:-1] * k)
        hi = np.maximum.reduceat(flat_uv, starts[:-1] * k)
        order = np.lexsort((-part_dist, owner))  # grouped by agent, far parts first
        polys = self._outlines(
            np.rint(uv * (1 << SUBPIXEL_BITS)).astype(np.int32),
            part_shift,
            geometry[:, k + 1 :],
            np.concatenate([m.faces for m in models]),
        )[order]
        radiance = radiance[order]

        clipped: dict[int, list[np.ndarray]] = {}
        drop = behind.copy()
        for i in np.flatnonzero(~in_front & ~behind).tolist():
            parts, lo[i], hi[i] = self._clipped_polygons(
                cam_pts[order[starts_l[i] : starts_l[i + 1]]]
            )
            clipped[i] = parts
            drop[i] = not parts

        agent_dist, motion = self._distance_and_motion(shift, to_cam, height, speed, rot)
        blurred = np.hypot(motion[:, 0], motion[:, 1]) >= MIN_BLUR_PX
        pad = np.where(blurred, np.ceil(np.abs(motion).max(axis=1)) + 2.0, 1.0)[:, None]
        h, w = self.canvas.shape
        size = np.array([w, h, w, h])
        box = np.concatenate([np.floor(lo) - pad, np.ceil(hi) + pad + 1.0], axis=1)
        box = np.minimum(np.maximum(box, 0.0), size).astype(np.int64)
        drop |= (box[:, 2] <= box[:, 0]) | (box[:, 3] <= box[:, 1])
        shown = np.flatnonzero(~drop)
        if len(shown) == 0:
            return [], boxes
        cut = np.zeros(n, dtype=bool)
        cut[shown] = nearest_occluder.of(box[shown]) < agent_dist[shown]

        far_first = shown[np.argsort(-agent_dist[shown], kind="stable")].tolist()
        ctx = _Frame(
            box.tolist(),
            agent_dist.tolist(),
            motion.tolist(),
            cut.tolist(),
            img,
            occluder_depth,
            labels,
            boxes,
        )
        drawn: list[DrawnAgent] = []
        batch: list[int] = []
        batch_parts = 0
        for i in far_first:
            if batch_parts + n_parts_l[i] > 255:
                drawn += self._draw_batch(batch, ctx, starts_l, polys, clipped, radiance)
                batch, batch_parts = [], 0
            batch.append(i)
            batch_parts += n_parts_l[i]
        drawn += self._draw_batch(batch, ctx, starts_l, polys, clipped, radiance)
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

    def _distance_and_motion(
        self,
        shift: np.ndarray,
        to_cam: np.ndarray,
        height_m: np.ndarray,
        speed_mps: np.ndarray,
        rot: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Each agent's distance from the lens (m) to its centre (half its height up) and its
        canvas displacement (N, 2) from time t back to t - exposure (0 without blur or when
        the agent is not in front). ``shift`` (N, 3) and ``to_cam`` (N, 3, 3) take each
        agent's model frame to the camera frame; ``rot`` is the camera's rotation."""
        now = shift + (0.5 * height_m)[:, None] * rot[:, 2]
        dist = np.sqrt(np.einsum("ij,ij->i", now, now))
        if not self.motion_blur:
            return dist, np.zeros((len(now), 2))
        # back over the exposure along the heading: the model's +x axis in the camera frame
        past = now - (self.exposure_s * speed_mps)[:, None] * to_cam[:, :, 0]
        uv = self._to_canvas(np.stack([now, past]))
        ok = (now[:, 2] >= Z_NEAR_M) & (past[:, 2] >= Z_NEAR_M)
        return dist, np.where(ok[:, None], uv[1] - uv[0], 0.0)

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
        ctx: _Frame,
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
            mine = cv2.compare(ranks[y0:y1, x0:x1], first[i] - 1, cv2.CMP_GT)
            silhouettes[i] = cv2.countNonZero(mine)
        drawn = []
        cluster_of = np.full(256, -1, np.intp)  # rank -> cluster
        clusters = _clusters([i for i in batch if silhouettes[i] > 0], ctx)
        for c, cluster in enumerate(clusters):
            for i in cluster.members:
                cluster_of[first[i] : end[i]] = c
        for c, cluster in enumerate(clusters):
            mine = cluster_of == c
            self._composite(cluster, ctx, lut * mine, names * mine, first, end)
            ctx.boxes.append(tuple(cluster.box))
            drawn += [
                DrawnAgent(i, i + 1, tuple(ctx.rois[i]), silhouettes[i]) for i in cluster.members
            ]
        for i in batch:
            x0, y0, x1, y1 = ctx.rois[i]
            ranks[y0:y1, x0:x1] = 0
        return drawn

    def _composite(
        self,
        cluster: _Cluster,
        ctx: _Frame,
        lut: np.ndarray,
        names: np.ndarray,
        first: dict[int, int],
        end: dict[int, int],
    ) -> None:
        """Occlusion cut, blur, composite and label one cluster of agents; ``lut`` and
        ``names`` give the radiance and label of its members' part ranks (0 for others)."""
        members = cluster.members
        x0, y0, x1, y1 = cluster.box
        ranks = self._ranks[y0:y1, x0:x1]
        depth = ctx.occluder_depth[y0:y1, x0:x1]
        cut = [i for i in members if ctx.cut[i]]
        if cut:
            # parts behind a nearer standing surface at time t are taken out before the smear
            dist = np.zeros(256, np.float32)
            for i in cut:
                dist[first[i] : end[i]] = ctx.dist[i]
            hidden = cv2.compare(depth, cv2.LUT(ranks, dist), cv2.CMP_LT)
            cv2.subtract(ranks, ranks, dst=ranks, mask=hidden)
        view = ctx.img[y0:y1, x0:x1]
        out = ctx.labels[y0:y1, x0:x1]
        du, dv = cluster.motion
        if math.hypot(du, dv) < MIN_BLUR_PX:
            # sharp: each member pixel simply takes the part's radiance and the member's label
            now = cv2.LUT(ranks, names)
            mask = now if now.dtype == np.uint8 else cv2.compare(now, 0, cv2.CMP_NE)
            cv2.copyTo(cv2.LUT(ranks, lut), mask, view)
            cv2.copyTo(now, mask, out)
            return
        h, w = ranks.shape
        buf, second = stacked_layers(h, w, du, dv)
        cv2.LUT(ranks, lut, dst=buf[:h])
        cv2.LUT(ranks, (names > 0).astype(np.float32), dst=buf[second:])
        buf = smear_stacked(buf, du, dv)
        value, coverage = buf[:h], buf[second:]
        if cut:
            # ... and what the smear carries behind a surface nearer than all of them
            nearest_m = min(ctx.dist[i] for i in members)
            visible = cv2.compare(depth, nearest_m, cv2.CMP_GE)
            if cv2.countNonZero(visible) < visible.size:
                value = cv2.bitwise_and(value, value, mask=visible)
                coverage = cv2.bitwise_and(coverage, coverage, mask=visible)
        cv2.subtract(view, cv2.multiply(view, coverage), dst=view)
        cv2.add(view, value, dst=view)
        covered = coverage > 0.5
        if len(members) == 1:
            out[covered] = members[0] + 1
            return
        # each covered pixel belongs to the member there at mid-exposure
        now = _shifted(cv2.LUT(ranks, names), round(du / 2), round(dv / 2))
        np.copyto(out, now, where=covered & (now > 0))


@dataclass(frozen=True)
class _Frame:
    """Per-agent figures of one paint call (plain lists: read one agent at a time) and the
    frame's buffers."""

    rois: list[list[int]]  # canvas boxes (x0, y0, x1, y1), blur margins included
    dist: list[float]
    motion: list[list[float]]  # canvas px from time t back to t - exposure
    cut: list[bool]  # a standing surface in its box is nearer than the agent
    img: np.ndarray
    occluder_depth: np.ndarray
    labels: np.ndarray
    boxes: list[tuple[int, int, int, int]]  # canvas boxes drawn on, filled as clusters are drawn


#: Two boxes are one cluster when their joint box holds at most this many more pixels
#: than the two apart (about what one more round of OpenCV calls costs).
CLUSTER_SLACK_PX = 1500


@dataclass
class _Cluster:
    """Agents drawn in one go: one blur (their mean motion), one box."""

    members: list[int]
    box: list[int]  # x0, y0, x1, y1
    motion_sum: list[float]

    @property
    def motion(self) -> tuple[float, float]:
        k = len(self.members)
        return self.motion_sum[0] / k, self.motion_sum[1] / k


def _clusters(agents: list[int], ctx: _Frame) -> list[_Cluster]:
    """Agents (far to near) split into clusters: boxes close together, image motions alike
    (``similar_motion``). Clusters come far to near (by their nearest member)."""
    clusters: list[_Cluster] = []
    rois, motion = ctx.rois, ctx.motion
    for i in agents:
        ax0, ay0, ax1, ay1 = rois[i]
        room = (ax1 - ax0) * (ay1 - ay0) + CLUSTER_SLACK_PX
        for c in clusters:
            cx0, cy0, cx1, cy1 = c.box
            x0, y0 = min(ax0, cx0), min(ay0, cy0)
            x1, y1 = max(ax1, cx1), max(ay1, cy1)
            if (x1 - x0) * (y1 - y0) > (cx1 - cx0) * (cy1 - cy0) + room:
                continue
            if similar_motion(c.motion, motion[i]):
                c.box[:] = x0, y0, x1, y1
                c.members.append(i)
                c.motion_sum[0] += motion[i][0]
                c.motion_sum[1] += motion[i][1]
                break
        else:
            clusters.append(_Cluster([i], [ax0, ay0, ax1, ay1], list(motion[i])))
    clusters.sort(key=lambda c: -ctx.dist[c.members[-1]])
    return clusters


def _shifted(img: np.ndarray, dx: int, dy: int) -> np.ndarray:
    """``img`` moved by (dx, dy) px, zeros where nothing moved in."""
    h, w = img.shape
    out = np.zeros_like(img)
    if abs(dx) < w and abs(dy) < h:
        out[max(dy, 0) : h + min(dy, 0), max(dx, 0) : w + min(dx, 0)] = img[
            max(-dy, 0) : h - max(dy, 0), max(-dx, 0) : w - max(dx, 0)
        ]
    return out
