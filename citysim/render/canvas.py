"""The ideal-pinhole drawing surface of one camera, and the lens-distortion remap.

The renderer draws every frame on an *undistorted* canvas and, when the lens
distorts, bends the finished frame once with ``cv2.remap``. Why this and not
projecting every vertex with distortion: distortion bends straight edges, so
the image of a convex part is no longer the hull of its distorted vertices;
and the distortion polynomial folds back far outside the image, which breaks
walls and roads that run past the camera. Remapping is exact up to bilinear
interpolation (the frame pixel ``p`` samples the canvas at
``undistort(p)``, precisely what ``CameraModel.project(distort=True)``
inverts) and costs one ~0.1 ms remap per frame.

Conventions: canvas pixel ``(col, row)`` is the ideal (undistorted) image
point ``(u, v) = (col + x0_px, row + y0_px)`` in OpenCV pixel coordinates
(pixel centres on integers). With distortion the canvas is larger than the
frame (barrel lenses see more than their pinhole), so it covers every frame
pixel's ideal position. World frame of docs/design/architecture.md, metres.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import cv2
import numpy as np

from detector.camera import CameraModel

#: Geometry in front of this camera-frame depth is drawn; nearer is clipped away.
Z_NEAR_M = 0.05
#: A canvas never grows past this multiple of the frame (wild distortion coefficients).
MAX_CANVAS_SCALE = 3.0


#: boxes whose frame box ``Canvas.frame_boxes`` keeps (forgotten all at once beyond this)
FRAME_BOX_MEMO_SIZE = 20_000


@dataclass(frozen=True, eq=False)
class Canvas:
    """One camera's drawing surface: per-pixel rays and the frame remap."""

    camera: CameraModel
    x0_px: int
    y0_px: int
    width_px: int
    height_px: int
    #: fixed-point maps for ``cv2.remap`` frame <- canvas, or None when frame == canvas
    remap_maps: tuple[np.ndarray, np.ndarray] | None
    #: (H, W, 3) float64 unit world direction of each canvas pixel's ray
    rays_world: np.ndarray
    #: (H, W) cosine between each ray and the optical axis
    cos_off_axis: np.ndarray
    #: (u, v) each (H, W) float32: frame position (distorted) of each canvas pixel; None when frame == canvas
    frame_uv: tuple[np.ndarray, np.ndarray] | None = None
    #: (H, W, 2) int16 map for ``cv2.remap`` frame <- canvas, each frame pixel's nearest canvas
    #: pixel (labels are remapped by it: ``frame_to_canvas_index``)
    nearest_map: np.ndarray | None = None

    @property
    def shape(self) -> tuple[int, int]:
        return (self.height_px, self.width_px)

    def project(self, points_world_m: np.ndarray) -> np.ndarray:
        """(N, 3) world points -> (N, 2) canvas coordinates (NaN behind the camera)."""
        uv = self.camera.project(points_world_m, distort=False)
        uv[:, 0] -= self.x0_px
        uv[:, 1] -= self.y0_px
        return uv

    def cam_to_canvas(self, points_cam_m: np.ndarray) -> np.ndarray:
        """(N, 3) camera-frame points with z > 0 -> (N, 2) canvas coordinates."""
        cam = self.camera
        z = points_cam_m[:, 2]
        return np.column_stack(
            [
                cam.fx_px * points_cam_m[:, 0] / z + cam.cx_px - self.x0_px,
                cam.fy_px * points_cam_m[:, 1] / z + cam.cy_px - self.y0_px,
            ]
        )

    def to_frame(self, canvas_img: np.ndarray, nearest: bool = False) -> np.ndarray:
        """A canvas-size image -> the camera's (distorted) frame."""
        if self.remap_maps is None:
            return canvas_img
        if nearest:
            return cv2.remap(
                canvas_img,
                self.nearest_map,
                None,
                cv2.INTER_NEAREST,
                borderMode=cv2.BORDER_REPLICATE,
            )
        return cv2.remap(
            canvas_img,
            self.remap_maps[0],
            self.remap_maps[1],
            cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_REPLICATE,
        )

    def frame_to_canvas_index(self) -> np.ndarray:
        """(frame H, frame W) int32: the flat index (row * canvas width + col) of the canvas
        pixel each frame pixel shows, by the nearest remap (border replicated)."""
        fh, fw = self.camera.height_px, self.camera.width_px
        if self.nearest_map is None:
            cols, rows = np.meshgrid(np.arange(fw), np.arange(fh))
        else:
            cols = np.clip(self.nearest_map[..., 0].astype(np.int64), 0, self.width_px - 1)
            rows = np.clip(self.nearest_map[..., 1].astype(np.int64), 0, self.height_px - 1)
        return (rows * self.width_px + cols).astype(np.int32)

    def spheres_in_view(self, centres_m: np.ndarray, radii_m: np.ndarray) -> np.ndarray:
        """(N,) bool: which spheres (world centres (N, 3), radii (N,)) may show on the canvas.

        Conservative: a sphere is dropped only when it lies wholly outside one of
        the canvas's four side planes or before the near plane.
        """
        p = self.camera.world_to_cam(centres_m)
        inside = (p @ self._side_normals.T) >= -radii_m[:, None]
        return np.all(inside, axis=1) & (p[:, 2] >= Z_NEAR_M - radii_m)

    @cached_property
    def _side_normals(self) -> np.ndarray:
        """(4, 3) inward unit normals (camera frame) of the planes through the canvas edges."""
        cam = self.camera
        a_l = (self.x0_px - 0.5 - cam.cx_px) / cam.fx_px
        a_r = (self.x0_px + self.width_px - 0.5 - cam.cx_px) / cam.fx_px
        b_t = (self.y0_px - 0.5 - cam.cy_px) / cam.fy_px
        b_b = (self.y0_px + self.height_px - 0.5 - cam.cy_px) / cam.fy_px
        normals = np.array([[1.0, 0.0, -a_l], [-1.0, 0.0, a_r], [0.0, 1.0, -b_t], [0.0, -1.0, b_b]])
        return normals / np.linalg.norm(normals, axis=1, keepdims=True)

    def frame_boxes(self, rois: np.ndarray) -> np.ndarray:
        """(N, 4) canvas boxes (x0, y0, x1, y1), exclusive ends -> (N, 4) frame boxes that
        hold everything of each canvas box, clipped to the frame (empty: x1 <= x0 or y1 <= y0).

        Each box's answer is kept: the same boxes come back frame after frame (swaying crowns,
        the glare of lamp heads), and an answer is a pure function of the box."""
        r = np.asarray(rois, dtype=np.int64).reshape(-1, 4)
        if self.frame_uv is None:
            return r.copy()
        memo = self._frame_box_memo
        keys = [tuple(row) for row in r.tolist()]
        missing = [k for k in dict.fromkeys(keys) if k not in memo]
        if missing:
            if len(memo) > FRAME_BOX_MEMO_SIZE:
                memo.clear()
            for k, box in zip(missing, self._frame_boxes(np.array(missing, np.int64)).tolist(), strict=True):
                memo[k] = box
        return np.array([memo[k] for k in keys], np.int64).reshape(-1, 4)

    @cached_property
    def _frame_box_memo(self) -> dict[tuple[int, ...], list[int]]:
        return {}

    def _frame_boxes(self, r: np.ndarray) -> np.ndarray:
        # the lens maps the box's border to its image's border, a gently bent rectangle: its
        # extremes are at the corners or edge midpoints (1 px of margin covers the bending)
        cols = np.column_stack([r[:, 0], (r[:, 0] + r[:, 2]) // 2, r[:, 2] - 1])
        rows = np.column_stack([r[:, 1], (r[:, 1] + r[:, 3]) // 2, r[:, 3] - 1])
        uv = self._frame_uv_stacked[rows[:, :, None], cols[:, None, :]].reshape(len(r), 9, 2)
        out = np.concatenate(
            [np.floor(uv.min(axis=1)) - 2.0, np.ceil(uv.max(axis=1)) + 3.0], axis=1
        )
        fw, fh = self.camera.width_px, self.camera.height_px
        return np.minimum(np.maximum(out, 0.0), [fw, fh, fw, fh]).astype(np.int64)

    @cached_property
    def _frame_uv_stacked(self) -> np.ndarray:
        return np.stack(self.frame_uv, axis=-1)

    def remap_box(self, canvas_img: np.ndarray, box: Sequence[int], out: np.ndarray) -> None:
        """Write the frame box ``box`` (x0, y0, x1, y1) of ``to_frame(canvas_img)`` into the
        same box of ``out`` (frame size), computing only that box."""
        x0, y0, x1, y1 = box
        if self.remap_maps is None:
            out[y0:y1, x0:x1] = canvas_img[y0:y1, x0:x1]
            return
        cv2.remap(
            canvas_img,
            self.remap_maps[0][y0:y1, x0:x1],
            self.remap_maps[1][y0:y1, x0:x1],
            cv2.INTER_LINEAR,
            dst=out[y0:y1, x0:x1],
            borderMode=cv2.BORDER_REPLICATE,
        )


def build_canvas(camera: CameraModel, distortion: bool) -> Canvas:
    """The canvas for ``camera``; with ``distortion`` and a distorting lens, a remapped one."""
    w, h = camera.width_px, camera.height_px
    maps = None
    frame_uv = None
    nearest_map = None
    x0 = y0 = 0
    cw, ch = w, h
    if distortion and camera.has_distortion:
        cols, rows = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
        ideal = camera.undistort_pixels(np.column_stack([cols.ravel(), rows.ravel()]))
        lim_x, lim_y = MAX_CANVAS_SCALE * w, MAX_CANVAS_SCALE * h
        ideal[:, 0] = np.clip(ideal[:, 0], w / 2 - lim_x / 2, w / 2 + lim_x / 2)
        ideal[:, 1] = np.clip(ideal[:, 1], h / 2 - lim_y / 2, h / 2 + lim_y / 2)
        x0 = int(np.floor(ideal[:, 0].min())) - 2
        y0 = int(np.floor(ideal[:, 1].min())) - 2
        cw = int(np.ceil(ideal[:, 0].max())) + 3 - x0
        ch = int(np.ceil(ideal[:, 1].max())) + 3 - y0
        map_x = (ideal[:, 0] - x0).reshape(h, w).astype(np.float32)
        map_y = (ideal[:, 1] - y0).reshape(h, w).astype(np.float32)
        maps = cv2.convertMaps(map_x, map_y, cv2.CV_16SC2)
        nearest_map = np.rint(np.stack([map_x, map_y], axis=-1)).astype(np.int16)
    cols, rows = np.meshgrid(
        np.arange(cw, dtype=np.float64) + x0, np.arange(ch, dtype=np.float64) + y0
    )
    rays_cam = np.stack(
        [
            (cols - camera.cx_px) / camera.fx_px,
            (rows - camera.cy_px) / camera.fy_px,
            np.ones_like(cols),
        ],
        axis=-1,
    )
    norm = np.linalg.norm(rays_cam, axis=-1)
    rays_cam /= norm[..., None]
    rays_world = rays_cam @ camera.rotation_world_to_cam
    if maps is not None:
        pts = (rays_cam / rays_cam[..., 2:]).reshape(-1, 1, 3)
        fwd, _ = cv2.projectPoints(
            pts, np.zeros(3), np.zeros(3), camera.intrinsic_matrix, camera.distortion
        )
        fwd = fwd.reshape(ch, cw, 2)
        frame_uv = (
            np.ascontiguousarray(fwd[..., 0], np.float32),
            np.ascontiguousarray(fwd[..., 1], np.float32),
        )
    return Canvas(
        camera,
        x0,
        y0,
        cw,
        ch,
        maps,
        rays_world,
        (1.0 / norm).astype(np.float32),
        frame_uv,
        nearest_map,
    )


def clip_solid_near(points_cam_m: np.ndarray, z_near_m: float = Z_NEAR_M) -> np.ndarray | None:
    """Clip one convex solid (K, 3 camera-frame vertices) to ``z >= z_near``.

    Returns the vertices of the clipped solid (their hull is exactly the solid
    cut by the plane: the cut of every vertex-to-vertex segment lies in the
    solid, and the cuts of its edges are among them), or None when nothing is
    in front.
    """
    front = points_cam_m[:, 2] >= z_near_m
    if front.all():
        return points_cam_m
    if not front.any():
        return None
    a, b = points_cam_m[front], points_cam_m[~front]
    za, zb = a[:, 2][:, None], b[:, 2][None, :]
    s = (z_near_m - za) / (zb - za)  # (Na, Nb) in (0, 1]
    cuts = a[:, None, :] + s[..., None] * (b[None, :, :] - a[:, None, :])
    return np.concatenate([a, cuts.reshape(-1, 3)])


def canvas_hull_px(canvas: Canvas, points_world_m: np.ndarray) -> np.ndarray | None:
    """Canvas coordinates (M, 2) of one convex solid's (K, 3 world) near-clipped vertices."""
    cam_pts = canvas.camera.world_to_cam(points_world_m)
    clipped = clip_solid_near(cam_pts)
    if clipped is None:
        return None
    return canvas.cam_to_canvas(clipped)


def roi_of(uv: np.ndarray, canvas: Canvas, margin_px: int = 1) -> tuple[int, int, int, int] | None:
    """Integer canvas box (x0, y0, x1, y1), exclusive ends, around points ``uv``; None if off-canvas."""
    lo = np.floor(uv.min(axis=0)) - margin_px
    hi = np.ceil(uv.max(axis=0)) + margin_px + 1
    x0, y0 = max(int(max(lo[0], -1e9)), 0), max(int(max(lo[1], -1e9)), 0)
    x1 = min(int(min(hi[0], 1e9)), canvas.width_px)
    y1 = min(int(min(hi[1], 1e9)), canvas.height_px)
    if x1 <= x0 or y1 <= y0:
        return None
    return x0, y0, x1, y1


#: Box minima are looked up on cells of this many pixels a side.
RANGE_MIN_CELL_PX = 8


class BoxMinimum:
    """Lower bound of an image's values over canvas boxes, for many boxes at once.

    The image is reduced to the minimum of each RANGE_MIN_CELL_PX square cell,
    and a 2-D sparse table (minima over 2^a x 2^b cells at every cell) answers
    each box with four look-ups. The bound is exact on cell boundaries and
    conservative (never above the true minimum) elsewhere.
    """

    def __init__(self, image: np.ndarray) -> None:
        c = RANGE_MIN_CELL_PX
        h, w = image.shape
        hc, wc = (h + c - 1) // c, (w + c - 1) // c
        padded = np.full((hc * c, wc * c), np.inf, np.float32)
        padded[:h, :w] = image
        cells = padded.reshape(hc, c, wc, c).min(axis=(1, 3))
        ly, lx = max(hc.bit_length() - 1, 0), max(wc.bit_length() - 1, 0)
        table = np.full((ly + 1, lx + 1, hc, wc), np.inf, np.float32)
        table[0, 0] = cells
        for a in range(ly + 1):
            if a > 0:
                s = 1 << (a - 1)
                table[a, 0, : hc - s] = np.minimum(table[a - 1, 0, : hc - s], table[a - 1, 0, s:])
            for b in range(1, lx + 1):
                s = 1 << (b - 1)
                table[a, b, :, : wc - s] = np.minimum(
                    table[a, b - 1, :, : wc - s], table[a, b - 1, :, s:]
                )
        self._table = table
        span = np.arange(max(hc, wc) + 1)
        self._log2 = np.zeros(len(span), np.int64)  # floor(log2(span)), span >= 1
        self._log2[1:] = np.floor(np.log2(span[1:])).astype(np.int64)

    def of(self, boxes: np.ndarray) -> np.ndarray:
        """(N,) minimum over each canvas box (N, 4) int (x0, y0, x1, y1), exclusive ends,
        non-empty and inside the canvas."""
        c = RANGE_MIN_CELL_PX
        b = np.asarray(boxes, dtype=np.int64).reshape(-1, 4)
        lo = b[:, :2] // c  # first cells (x, y)
        hi = (b[:, 2:] - 1) // c + 1  # one past the last cells
        level = self._log2[hi - lo]  # (N, 2): the largest power of two in each span
        start = hi - (1 << level)
        t = self._table
        kx, ky = level[:, 0], level[:, 1]
        return np.minimum(
            np.minimum(t[ky, kx, lo[:, 1], lo[:, 0]], t[ky, kx, lo[:, 1], start[:, 0]]),
            np.minimum(t[ky, kx, start[:, 1], lo[:, 0]], t[ky, kx, start[:, 1], start[:, 0]]),
        )


def overlapping_groups(
    boxes: list[tuple[int, int, int, int]],
) -> list[tuple[list[int], tuple[int, int, int, int]]]:
    """Boxes (x0, y0, x1, y1) in groups that overlap (directly or through others): (indices
    in order, the group's joint box). A group is redrawn as a whole, in order."""
    groups: list[tuple[list[int], list[int]]] = []
    for i, (x0, y0, x1, y1) in enumerate(boxes):
        members, box = [i], [x0, y0, x1, y1]
        for g in list(groups):
            gx0, gy0, gx1, gy1 = g[1]
            if box[0] < gx1 and gx0 < box[2] and box[1] < gy1 and gy0 < box[3]:
                groups.remove(g)
                members = g[0] + members
                box = [min(box[0], gx0), min(box[1], gy0), max(box[2], gx1), max(box[3], gy1)]
        groups.append((members, box))
    return [(sorted(m), tuple(b)) for m, b in groups]
