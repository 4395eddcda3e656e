"""Silhouettes of the ``detector.train.shapes`` models: projection and rasterisation.

A model's silhouette in a camera's frame is the union of the convex hulls of
its projected parts (each part is a convex solid). The classifier's training
regions (``detector.train.sets``) and the detector's tests rasterise models
with these functions.

Conventions: pixels are OpenCV's (u right, v down, pixel centres on
integers); projection is ``CameraModel.project`` (distorted by default, NaN
behind the camera); masks are uint8 {0, 255} cropped to the model, with the
crop's top-left pixel ``offset_px`` (x0, y0) in the full frame. Hulls are
filled with ``SUBPIXEL_BITS`` bits of sub-pixel precision.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import cv2
import numpy as np

from detector.camera import CameraModel

if TYPE_CHECKING:
    from detector.train.shape_parts import Shape

SUBPIXEL_BITS = 4


@dataclass(frozen=True)
class Silhouette:
    """A rasterised model: ``mask`` (h, w) uint8 {0, 255} cropped at ``offset_px`` (x0, y0)
    of the full frame, and whether the model reaches the frame border."""

    mask: np.ndarray
    offset_px: tuple[int, int]
    touches_border: bool


def project_parts(camera: CameraModel, corners_m: np.ndarray, distort: bool = True) -> np.ndarray:
    """(P, K, 3) world vertices -> (P, K, 2) pixels (OpenCV convention, NaN behind the camera)."""
    p, k, _ = corners_m.shape
    return camera.project(corners_m.reshape(-1, 3), distort=distort).reshape(p, k, 2)


def rasterise_parts(
    uv_px: np.ndarray, width_px: int, height_px: int, margin_px: int = 1
) -> Silhouette | None:
    """Fill the convex hull of every part's projected vertices (P, K, 2) on a cropped canvas.

    Parts with a vertex behind the camera are skipped (their projection is not
    the image of a convex solid). Pixel centres lie on integer coordinates, so
    a pixel is set when its centre falls inside a part. Returns None when
    nothing lands in the frame.
    """
    ok = np.all(np.isfinite(uv_px), axis=(1, 2))
    if not np.any(ok):
        return None
    uv = uv_px[ok]
    lo = np.floor(uv.reshape(-1, 2).min(axis=0)).astype(int) - margin_px
    hi = np.ceil(uv.reshape(-1, 2).max(axis=0)).astype(int) + margin_px
    x0, y0 = max(lo[0], 0), max(lo[1], 0)
    x1, y1 = min(hi[0], width_px - 1), min(hi[1], height_px - 1)
    if x1 < x0 or y1 < y0:
        return None
    mask = np.zeros((y1 - y0 + 1, x1 - x0 + 1), np.uint8)
    scale = 1 << SUBPIXEL_BITS
    fixed = np.round((uv - np.array([x0, y0])) * scale).astype(np.int32)
    for part in fixed:
        hull = cv2.convexHull(part)
        cv2.fillConvexPoly(mask, hull, 255, lineType=cv2.LINE_8, shift=SUBPIXEL_BITS)
    if not mask.any():
        return None
    touches = bool(
        (x0 == 0 and mask[:, 0].any())
        or (y0 == 0 and mask[0].any())
        or (x1 == width_px - 1 and mask[:, -1].any())
        or (y1 == height_px - 1 and mask[-1].any())
    )
    return Silhouette(mask, (int(x0), int(y0)), touches)


def silhouette_mask(camera: CameraModel, shape: Shape, distort: bool = True) -> Silhouette | None:
    """The model's silhouette in ``camera``'s frame (cropped), or None if it is out of view."""
    uv = project_parts(camera, shape.corners_m, distort=distort)
    return rasterise_parts(uv, camera.width_px, camera.height_px)
