"""The static background of one camera: ray-cast once, re-lit every frame.

At construction every canvas pixel's ray is cast against the ground plane and
the street's solids (``citysim.render.scenery``), which gives per pixel the
surface, its distance, normal and reflectance. From those:

* ``base``: radiance from the IR emitter, daylight and sky glow (fixed);
* one *pool* image per street lamp that reaches the view: its light at level 1,
  so a frame's background is ``base + sum(level_i * pool_i)`` - a few
  vectorised multiply-adds, no per-pixel Python;
* ``occluder_depth``: distance to the nearest *standing* surface (inf on the
  ground and sky), against which agents are hidden;
* per visible ground pixel its world point and reflectance, for headlight
  spots.

Tree crowns, when they sway, are kept as sprites (their own radiance, alpha
and depth) pre-rendered in a few poses across their sway; the renderer keeps
them composited at their current poses in its cached still view and redraws
a group of overlapping crowns only when one of them changes pose (``sway``).

Conventions: canvas of ``citysim.render.canvas`` (ideal pinhole pixels),
radiance in linear full-scale units of ``citysim.render.light``, distances in
metres along each pixel's ray.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from citysim.render import light
from citysim.render.canvas import BoxMinimum, Canvas, canvas_hull_px, overlapping_groups, roi_of
from citysim.render.crowns import (
    SWAY_M_PER_MPS,
    SWAY_MIN_PX,
    SWAY_POSES,
    CrownSprite,
    draw_sway,
    sway_px,
)
from citysim.render.scenery import Ellipsoid, Solid, _grain, ground_reflectance, scenery_parts
from citysim.world.street import Street

#: A lamp whose light adds less than this radiance anywhere in view is ignored.
POOL_MIN_RADIANCE = 2e-5
#: Leaf texture: crowns are patchy, not painted boxes.
LEAF_TEXTURE_AMPLITUDE = 0.3
FAR_DEPTH_M = 1e9


@dataclass(frozen=True, eq=False)
class LampPool:
    """One lamp's light on the static scene at level 1, over a canvas box (x0, y0, x1, y1)."""

    lamp_index: int
    roi: tuple[int, int, int, int]
    radiance: np.ndarray


@dataclass(frozen=True)
class ShadingInputs:
    ambient_light: float
    ir_emitter_power: float
    lamp_positions_m: np.ndarray  # (L, 3) luminaires


def shade_surfaces(
    canvas: Canvas,
    flat_idx: np.ndarray,
    t_m: np.ndarray,
    normals: np.ndarray,
    rho: np.ndarray,
    shading: ShadingInputs,
) -> tuple[np.ndarray, np.ndarray]:
    """Radiance of N hit pixels: (base (N,), lamp components (N, L) at level 1)."""
    dirs = canvas.rays_world.reshape(-1, 3)[flat_idx]
    cos_inc = np.abs(np.einsum("nk,nk->n", dirs, normals))
    cos_axis = canvas.cos_off_axis.reshape(-1)[flat_idx]
    irr = light.emitter_irradiance(
        shading.ir_emitter_power, shading.ambient_light, t_m, cos_inc, cos_axis
    )
    irr = irr + light.day_irradiance(shading.ambient_light, normals[:, 2])
    irr = irr + light.night_irradiance(shading.ambient_light)
    points = canvas.camera.position_m + dirs * t_m[:, None]
    lamps = light.lamp_irradiance(points, normals, shading.lamp_positions_m)
    return rho * irr, rho[:, None] * lamps


def _roi_indices(roi: tuple[int, int, int, int], width_px: int) -> np.ndarray:
    x0, y0, x1, y1 = roi
    rows = np.arange(y0, y1)[:, None]
    cols = np.arange(x0, x1)[None, :]
    return (rows * width_px + cols).ravel()


def _cast_solids(
    canvas: Canvas, solids: tuple[Solid, ...], n_pixels: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nearest solid per canvas pixel: (t_m (N,), normals (N, 3), reflectance (N,))."""
    dirs = canvas.rays_world.reshape(-1, 3)
    origin = canvas.camera.position_m
    depth = np.full(n_pixels, np.inf)
    normals = np.zeros((n_pixels, 3))
    rho = np.zeros(n_pixels)
    for solid in solids:
        uv = canvas_hull_px(canvas, solid.corners_m())
        roi = None if uv is None else roi_of(uv, canvas)
        if roi is None:
            continue
        idx = _roi_indices(roi, canvas.width_px)
        t, n = solid.cast(origin, dirs[idx])
        nearer = t < depth[idx]
        if not nearer.any():
            continue
        sel = idx[nearer]
        depth[sel] = t[nearer]
        normals[sel] = n[nearer]
        r = np.full(len(sel), solid.ir_reflectance)
        if isinstance(solid, Ellipsoid):
            hit = origin + dirs[sel] * t[nearer][:, None]
            r *= 1.0 + LEAF_TEXTURE_AMPLITUDE * _grain(
                hit[:, 0] + 0.7 * hit[:, 2], hit[:, 1] - 0.5 * hit[:, 2]
            )
        rho[sel] = r
    return depth, normals, rho


class StaticScene:
    """Everything about one camera's view that does not move (see module docstring)."""

    def __init__(
        self,
        canvas: Canvas,
        street: Street,
        shading: ShadingInputs,
        rng: np.random.Generator,
        sway: bool,
        wind_mps: float,
    ) -> None:
        self.canvas = canvas
        self.shading = shading
        cam = canvas.camera
        h, w = canvas.shape
        n = h * w
        parts = scenery_parts(street, (cam.x_m, cam.y_m))
        amplitude_m = SWAY_M_PER_MPS * wind_mps if sway else 0.0
        # every crown draws its sway whether or not it moves in this view, so the random
        # stream does not depend on what this camera sees
        sway_draws = [draw_sway(rng) for _ in parts.crowns]
        swaying = [sway_px(canvas, c, amplitude_m) >= SWAY_MIN_PX for c in parts.crowns]
        baked = tuple(c for c, moves in zip(parts.crowns, swaying, strict=True) if not moves)
        depth, normals, rho = _cast_solids(canvas, parts.solids + baked, n)
        self.occluder_depth = (
            np.where(np.isfinite(depth), depth, FAR_DEPTH_M).astype(np.float32).reshape(h, w)
        )

        dirs = canvas.rays_world.reshape(-1, 3)
        with np.errstate(divide="ignore"):
            t_ground = np.where(dirs[:, 2] < -1e-9, -cam.height_m / dirs[:, 2], np.inf)
        ground = t_ground < depth
        gpts = cam.position_m + dirs[ground] * t_ground[ground][:, None]
        depth[ground] = t_ground[ground]
        normals[ground] = (0.0, 0.0, 1.0)
        rho[ground] = ground_reflectance(street, gpts[:, 0], gpts[:, 1])

        # ground (x, y, 1) -> canvas pixel (homogeneous): K [r1 r2 t], shifted to the canvas
        rot = cam.rotation_world_to_cam
        shift = np.array([[1.0, 0.0, -canvas.x0_px], [0.0, 1.0, -canvas.y0_px], [0.0, 0.0, 1.0]])
        self.ground_to_canvas = (
            shift
            @ cam.intrinsic_matrix
            @ np.column_stack([rot[:, 0], rot[:, 1], -rot @ cam.position_m])
        )
        # camera-frame depth of the nearest ground the camera sees: carried-light spots are clipped there
        ground_cam_z = t_ground[ground] * canvas.cos_off_axis.reshape(-1)[ground]
        self.nearest_ground_cam_z_m = float(ground_cam_z.min()) if ground.any() else FAR_DEPTH_M
        self.ground_xy_m = np.full((n, 2), np.nan, dtype=np.float32)
        self.ground_xy_m[ground] = gpts[:, :2]
        self.ground_xy_m = self.ground_xy_m.reshape(h, w, 2)
        self.ground_reflectance = np.zeros(n, dtype=np.float32)
        self.ground_reflectance[ground] = rho[ground]
        self.ground_reflectance = self.ground_reflectance.reshape(h, w)

        hit = np.flatnonzero(np.isfinite(depth))
        base_hit, pools_hit = shade_surfaces(
            canvas, hit, depth[hit], normals[hit], rho[hit], shading
        )
        base = np.full(n, light.sky_radiance(shading.ambient_light), dtype=np.float32)
        base[hit] = base_hit
        self.base = base.reshape(h, w)
        self.pools = self._pools(hit, pools_hit, n)
        sprites = (
            self._crown_sprite(c, amplitude_m, draw)
            for c, draw, moves in zip(parts.crowns, sway_draws, swaying, strict=True)
            if moves
        )
        self.crowns = tuple(c for c in sprites if c is not None)
        reach = self.occluder_depth.copy()
        for crown in self.crowns:  # wherever a crown may sway, it may hide what is behind
            x0, y0, x1, y1 = crown.roi
            np.minimum(reach[y0:y1, x0:x1], crown.near_m, out=reach[y0:y1, x0:x1])
        #: lower bound of the frame's occluder depth over canvas boxes, whatever the sway
        self.nearest_occluder = BoxMinimum(reach)
        self._lit_key: tuple[float, ...] | None = None
        self._lit = self.base
        self._depth: np.ndarray | None = None  # this frame's depth, when crowns sway
        self._poses: list[int] = [-1] * len(self.crowns)  # the poses drawn in the still view
        self._crown_groups = overlapping_groups([c.roi for c in self.crowns])
        self._crown_values: list[tuple] = [(None, {}) for _ in self.crowns]  # see _crown_value

    # ------------------------------------------------------------------ build
    def _pools(self, hit: np.ndarray, pools_hit: np.ndarray, n: int) -> tuple[LampPool, ...]:
        h, w = self.canvas.shape
        out = []
        for j in range(pools_hit.shape[1]):
            col = pools_hit[:, j]
            lit = col > POOL_MIN_RADIANCE
            if not lit.any():
                continue
            full = np.zeros(n, dtype=np.float32)
            full[hit] = col
            rows, cols = np.divmod(hit[lit], w)
            roi = (int(cols.min()), int(rows.min()), int(cols.max()) + 1, int(rows.max()) + 1)
            img = full.reshape(h, w)[roi[1] : roi[3], roi[0] : roi[2]].copy()
            out.append(LampPool(j, roi, img))
        return tuple(out)

    def _crown_sprite(
        self, crown: Ellipsoid, amplitude_m: float, draw: tuple[float, float, tuple[float, float]]
    ) -> CrownSprite | None:
        canvas = self.canvas
        angle, freq_hz, phases = draw
        grown = Ellipsoid(crown.centre_m, crown.radii_m + amplitude_m, crown.ir_reflectance)
        uv = canvas_hull_px(canvas, grown.corners_m())
        roi = None if uv is None else roi_of(uv, canvas, margin_px=2)
        if roi is None:
            return None
        idx = _roi_indices(roi, canvas.width_px)
        depth, normals, rho = _cast_solids(canvas, (crown,), canvas.width_px * canvas.height_px)
        t = depth[idx]
        hit = np.isfinite(t)
        if not hit.any():
            return None
        base_hit, pools_hit = shade_surfaces(
            canvas, idx[hit], t[hit], normals[idx][hit], rho[idx][hit], self.shading
        )
        shape = (roi[3] - roi[1], roi[2] - roi[0])

        def sprite(
            values: np.ndarray, fill: float
        ) -> np.ndarray:  # alpha is 1 on hits: premultiplied
            out = np.full(len(idx), fill, dtype=np.float32)
            out[hit] = values
            return out.reshape(shape)

        pools = tuple(
            (j, sprite(pools_hit[:, j], 0.0))
            for j in range(pools_hit.shape[1])
            if pools_hit[:, j].max() > POOL_MIN_RADIANCE
        )
        near_m = float(t[hit].min())
        x0, y0, x1, y1 = roi
        behind = (self.occluder_depth[y0:y1, x0:x1] > near_m).astype(np.float32)
        # image shift per metre of sway, linearised (the sway is centimetres)
        c = crown.centre_m
        uv = canvas.project(np.array([c, c + [0.01, 0.0, 0.0], c + [0.0, 0.01, 0.0]]))
        jacobian = np.column_stack([uv[1] - uv[0], uv[2] - uv[0]]) / 0.01
        extreme_px = jacobian @ (amplitude_m * np.array([math.cos(angle), math.sin(angle)]))
        size = (shape[1], shape[0])

        def poses(img: np.ndarray) -> tuple[np.ndarray, ...]:
            out = []
            for s in np.linspace(-1.0, 1.0, SWAY_POSES):
                du, dv = s * extreme_px
                shift = np.array([[1.0, 0.0, du], [0.0, 1.0, dv]])
                moved = cv2.warpAffine(img, shift, size, flags=cv2.INTER_LINEAR, borderValue=0.0)
                out.append(cv2.multiply(moved, behind))  # nearer static things stay in front
            return tuple(out)

        alpha = poses(sprite(np.ones(hit.sum()), 0.0))
        return CrownSprite(
            roi,
            near_m,
            alpha,
            tuple(a > 0.5 for a in alpha),
            poses(sprite(base_hit, 0.0)),
            tuple((j, poses(pool)) for j, pool in pools),
            float(freq_hz),
            phases,
        )

    # -------------------------------------------------------------- per frame
    def lit(self, lamp_levels: np.ndarray) -> tuple[tuple[float, ...], np.ndarray]:
        """The background lit by the lamps at ``lamp_levels``, crowns at rest left out:
        (key of the lighting, radiance (H, W) float32; cached - do not write to it)."""
        key = tuple(float(lamp_levels[pool.lamp_index]) for pool in self.pools)
        if key != self._lit_key:  # lamps change level now and then: re-light only then
            lit = self.base.copy()
            for pool, level in zip(self.pools, key, strict=True):
                if level > 0.0:
                    x0, y0, x1, y1 = pool.roi
                    view = lit[y0:y1, x0:x1]
                    cv2.scaleAdd(pool.radiance, level, view, dst=view)
            self._lit, self._lit_key = lit, key
        return key, self._lit

    @property
    def depth(self) -> np.ndarray:
        """The depth of standing surfaces with the crowns at the poses last drawn."""
        return self.occluder_depth if self._depth is None else self._depth

    def sway(
        self, t_s: float, lamp_levels: np.ndarray, still: np.ndarray, relit: bool
    ) -> tuple[np.ndarray, list[tuple[int, int, int, int]]]:
        """Keep the swaying crowns in ``still`` - the lit background (``lit``), crowns
        composited at their poses - at their poses of time t: redraws only the groups of
        (overlapping) crowns whose pose changed, or all when ``relit`` (``still`` was just
        reset to the lit background). Returns this frame's depth of standing surfaces
        ((H, W) float32, do not write to it) and the canvas boxes of ``still`` redrawn."""
        if not self.crowns:
            return self.occluder_depth, []
        if self._depth is None:
            self._depth = self.occluder_depth.copy()
        poses = [crown.pose(t_s) for crown in self.crowns]
        boxes = []
        for members, (x0, y0, x1, y1) in self._crown_groups:
            if not relit and all(poses[i] == self._poses[i] for i in members):
                continue
            if not relit:
                still[y0:y1, x0:x1] = self._lit[y0:y1, x0:x1]
            self._depth[y0:y1, x0:x1] = self.occluder_depth[y0:y1, x0:x1]
            for i in members:
                self._composite_crown(i, poses[i], lamp_levels, still, self._depth)
            boxes.append((x0, y0, x1, y1))
        self._poses = poses
        return self._depth, boxes

    def _crown_value(self, index: int, pose: int, lamp_levels: np.ndarray) -> np.ndarray:
        """Crown ``index``'s radiance x alpha in ``pose`` lit by the lamps at ``lamp_levels``
        (do not write to it). Kept per pose while the levels of the lamps lighting the crown
        stay the same: the crowns sway through a few poses every second, and relighting one
        costs a multiply-add per lamp reaching it."""
        crown = self.crowns[index]
        key = tuple(float(lamp_levels[j]) for j, _ in crown.pools)
        cached_key, values = self._crown_values[index]
        if key != cached_key:
            values = {}
            self._crown_values[index] = (key, values)
        value = values.get(pose)
        if value is None:
            value = crown.base[pose]
            for (_, pool), level in zip(crown.pools, key, strict=True):
                if level > 0.0:
                    value = cv2.scaleAdd(pool[pose], level, value)
            values[pose] = value
        return value

    def _composite_crown(
        self,
        index: int,
        pose: int,
        lamp_levels: np.ndarray,
        img: np.ndarray,
        depth: np.ndarray,
    ) -> None:
        crown, k = self.crowns[index], pose
        value = self._crown_value(index, k, lamp_levels)
        alpha = crown.alpha[k]
        x0, y0, x1, y1 = crown.roi
        view = img[y0:y1, x0:x1]
        cv2.subtract(view, cv2.multiply(view, alpha), dst=view)
        cv2.add(view, value, dst=view)
        depth[y0:y1, x0:x1][crown.covered[k]] = crown.near_m
