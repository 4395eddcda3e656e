"""Moving agents on the canvas: articulated shapes, IR shading, motion blur, occlusion.

Each ``AgentState`` becomes the detector's own 3D model (``citysim.render.models``); every agent
of a frame is posed, projected, shaded, filled far to near and clustered at once, in compiled
loops (``citysim.render.kernels``). Agents straddling the camera's near plane are clipped part
by part (rare).

Conventions: canvas pixels of ``citysim.render.canvas``; world frame of
docs/design/architecture.md; ``heading_rad`` CCW from +x; radiance in linear full-scale units.

Design: docs/design/modules.md (Camera frames)
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from citysim.render import light
from citysim.render.blur import MIN_BLUR_PX
from citysim.render.canvas import Z_NEAR_M, BoxMinimum, Canvas, clip_solid_near
from citysim.render.clusters import PaintFrame, clusters, composite
from citysim.render.kernels import SUBPIXEL_BITS, agent_box, clear_boxes, fill_ranks, pose_parts
from citysim.render.models import draw_models
from citysim.render.outline import outline_tables
from citysim.world.agents import AgentState
from detector.train.shape_parts import VERTICES_PER_PART

#: Clothes, paint and fur face the camera at varied angles; one mean incidence cosine.
MEAN_INCIDENCE_COS = 0.8

__all__ = ["AgentLighting", "AgentPainter", "DrawnAgent", "part_radiance"]


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

    @property
    def constants(self) -> np.ndarray:
        """What ``citysim.render.kernels.pose_parts`` takes as ``light``."""
        return np.array([self.emitter_gain, self.uniform_irradiance, light.BEAM_EXPONENT])


def part_radiance(
    cam_centres_m: np.ndarray,
    world_centres_m: np.ndarray | None,
    rho: np.ndarray,
    lighting: AgentLighting,
) -> np.ndarray:
    """Parts' radiance from their centres in the camera frame (N, 3; the emitter's view) and
    the world (N, 3; the lamps' view) and their reflectances (N,): the plain numpy statement
    of what ``citysim.render.kernels.pose_parts`` computes per part (tests hold the two equal)."""
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


@dataclass(frozen=True)
class PosedParts:
    """A frame's agents posed for drawing (``citysim.render.kernels.pose_parts`` names the arrays)."""

    starts: list[int]  # agent i's parts are [starts[i], starts[i + 1])
    owner: np.ndarray  # (P,) agent of each part
    cam_pts: np.ndarray  # (P, K, 3) camera-frame vertices, m
    polys: np.ndarray  # (P, K, 2) int32 fixed-point canvas outlines
    radiance: np.ndarray  # (P,) float32
    part_dist: np.ndarray  # (P,) squared distance of each part centre, m^2
    agent_z: np.ndarray  # (N, 2) nearest and farthest vertex depth, m
    view: np.ndarray  # (N, 7) distance, image motion, canvas box (empty: out of view)


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
        self._camera_px = np.array(
            [cam.fx_px, cam.fy_px, cam.cx_px - canvas.x0_px, cam.cy_px - canvas.y0_px]
        )

    def pose(self, agents: Sequence[AgentState], lighting: AgentLighting) -> PosedParts:
        """Every part of ``agents`` posed, projected and shaded (``citysim.render.kernels.pose_parts``);
        parts without an outline table get their hull."""
        n = len(agents)
        models = draw_models(agents)
        n_parts = [m.n_parts for m in models]
        starts = [0, *itertools.accumulate(n_parts)]
        n_total = starts[-1]
        k = VERTICES_PER_PART
        posed = PosedParts(
            starts=starts,
            owner=np.repeat(np.arange(n), n_parts),
            cam_pts=np.empty((n_total, k, 3)),
            polys=np.empty((n_total, k, 2), np.int32),
            radiance=np.empty(n_total, np.float32),
            part_dist=np.empty(n_total),
            agent_z=np.empty((n, 2)),
            view=np.empty((n, 7)),
        )
        needs_hull = np.empty(n_total, np.bool_)
        pose_parts(
            np.concatenate([m.geometry for m in models]),
            np.concatenate([m.faces for m in models]),
            posed.owner,
            np.array([(a.x_m, a.y_m, a.heading_rad, a.height_m, a.speed_mps) for a in agents]),
            self._rot,
            self._pole,
            self._camera_px,
            outline_tables(),
            np.concatenate([m.reflectance for m in models]),
            lighting.constants,
            lighting.lamp_positions_m,
            lighting.lamp_levels,
            self.exposure_s if self.motion_blur else 0.0,
            Z_NEAR_M,
            MIN_BLUR_PX,
            np.array(self.canvas.shape[::-1], np.int64),
            posed.cam_pts,
            posed.polys,
            needs_hull,
            posed.radiance,
            posed.part_dist,
            posed.agent_z,
            posed.view,
        )
        for j in np.flatnonzero(needs_hull).tolist():
            hull = cv2.convexHull(posed.polys[j])[:, 0]
            posed.polys[j] = np.concatenate([hull, np.repeat(hull[-1:], k - len(hull), 0)])
        return posed

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
        posed = self.pose(agents, lighting)
        starts, owner, view, agent_z = posed.starts, posed.owner, posed.view, posed.agent_z
        n_parts = np.diff(starts).tolist()
        order = np.lexsort((-posed.part_dist, owner))  # grouped by agent, far parts first
        polys, radiance, cam_pts = posed.polys[order], posed.radiance[order], posed.cam_pts
        straddle, behind = [], set()
        if agent_z[:, 0].min() < Z_NEAR_M:  # wholly behind the camera: dropped; straddling: clipped
            behind = set(np.flatnonzero(agent_z[:, 1] < Z_NEAR_M).tolist())
            straddle = [
                i for i in np.flatnonzero(agent_z[:, 0] < Z_NEAR_M).tolist() if i not in behind
            ]
        h, w = self.canvas.shape
        clipped: dict[int, list[np.ndarray]] = {}
        for i in straddle:
            parts, lo, hi = self._clipped_polygons(cam_pts[order[starts[i] : starts[i + 1]]])
            clipped[i] = parts
            view[i, 3:7] = agent_box(np.array(lo + hi), view[i, 1], view[i, 2], MIN_BLUR_PX, w, h)
            if not parts:
                behind.add(i)
        dist = view[:, 0].tolist()
        motion = [tuple(m) for m in view[:, 1:3].tolist()]
        rois = [tuple(r) for r in view[:, 3:7].astype(np.int64).tolist()]
        shown = [
            i for i, (x0, y0, x1, y1) in enumerate(rois) if x1 > x0 and y1 > y0 and i not in behind
        ]
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
        batch_arr = np.array(batch)
        first_part = np.asarray(starts)[batch_arr]
        counts = np.asarray(starts)[batch_arr + 1] - first_part
        agent_parts = np.zeros(len(batch) + 1, np.int64)
        np.cumsum(counts, out=agent_parts[1:])
        n_batch = int(agent_parts[-1])
        # the batch's parts in drawing order: part p of the batch gets rank p + 1
        take = np.arange(n_batch) + np.repeat(first_part - agent_parts[:-1], counts)
        outlines = polys[take]
        n_verts = np.full(n_batch, outlines.shape[1], np.int64)
        if clipped:
            outlines, n_verts = _with_clipped(outlines, n_verts, batch, agent_parts, clipped)
        lut = np.zeros(256, np.float32)  # rank -> radiance
        lut[1 : n_batch + 1] = radiance[take]
        names = np.zeros(256, ctx.labels.dtype)  # rank -> label
        names[1 : n_batch + 1] = np.repeat(batch_arr + 1, counts)
        rois = np.array([ctx.rois[i] for i in batch], np.int64)
        sil = np.empty(len(batch), np.int64)
        fill_ranks(ranks, outlines, n_verts, agent_parts, rois, sil)
        bounds = agent_parts.tolist()
        first = {i: bounds[k] + 1 for k, i in enumerate(batch)}
        end = {i: bounds[k + 1] + 1 for k, i in enumerate(batch)}
        silhouettes = dict(zip(batch, sil.tolist(), strict=True))
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
        clear_boxes(ranks, rois)
        return drawn


def _with_clipped(
    outlines: np.ndarray,
    n_verts: np.ndarray,
    batch: list[int],
    agent_parts: np.ndarray,
    clipped: dict[int, list[np.ndarray]],
) -> tuple[np.ndarray, np.ndarray]:
    """The batch's outlines with the parts of agents cut at the near plane put in: their
    hulls, padded to one length (an empty part draws nothing)."""
    hulls = {}
    longest = outlines.shape[1]
    for k, i in enumerate(batch):
        if i in clipped:
            for j, poly in enumerate(clipped[i]):
                hull = cv2.convexHull(poly)[:, 0] if len(poly) else poly.reshape(0, 2)
                hulls[int(agent_parts[k]) + j] = hull
                longest = max(longest, len(hull))
    if longest > outlines.shape[1]:
        pad = np.repeat(outlines[:, -1:], longest - outlines.shape[1], axis=1)
        outlines = np.concatenate([outlines, pad], axis=1)
    for p, hull in hulls.items():
        n_verts[p] = len(hull)
        outlines[p, : len(hull)] = hull
    return outlines, n_verts
