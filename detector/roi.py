"""Region of interest per camera: the part of the frame where a target within range can appear.

``Crop`` is a band of rows (and the columns holding them), computed once from the
``CameraModel``, plus margins for distortion and the morphology's reach, so the segmenter runs
on the band alone and a target within range is segmented exactly as on the full frame.

Conventions: pixels are OpenCV's (u right, v down, pixel centres on integers, rows and columns
of the distorted frame); a crop is the half-open rows ``top_px .. bottom_px - 1`` and columns
``left_px .. right_px - 1``, its equalised part ``Crop.clahe_px`` likewise.

Design: docs/design/region-of-interest.md
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from detector.camera import CameraModel
from detector.classes import TABLE1

#: Table 1's tallest target, m (pedestrians, groups and vehicles reach 2.0 m).
TALLEST_TARGET_M = max(size.height_m[1] for size in TABLE1.values())

# pixels, beyond the band: lens distortion (undistortion error, tested at pixel centres) and rounding
_DISTORTION_MARGIN_PX = 1
# columns undistorted (all rows of each) to find a distorted band: every step-th, the centre
# column and the edges, where radial distortion puts the band's extremes (~15 ms at 240 rows)
_BAND_COLUMNS = 64


@dataclass(frozen=True)
class Crop:
    """Rows ``top_px .. bottom_px - 1`` and columns ``left_px .. right_px - 1`` (the part
    segmented) of a frame of ``frame_height_px`` x ``frame_width_px``; CLAHE equalises the part
    ``clahe_px`` (top, bottom, left, right, holding the crop) on a grid of ``clahe_tiles``
    (tiles across, tiles down)."""

    top_px: int
    bottom_px: int
    left_px: int
    right_px: int
    frame_height_px: int
    frame_width_px: int
    clahe_px: tuple[int, int, int, int]
    clahe_tiles: tuple[int, int]

    def __post_init__(self) -> None:
        top, bottom, left, right = self.clahe_px
        if not (
            0 <= top <= self.top_px < self.bottom_px <= bottom <= self.frame_height_px
            and 0 <= left <= self.left_px < self.right_px <= right <= self.frame_width_px
        ):
            raise ValueError(
                f"Crop rows {self.top_px}..{self.bottom_px} x columns {self.left_px}.."
                f"{self.right_px}, equalised {self.clahe_px}, do not fit a "
                f"{self.frame_height_px} x {self.frame_width_px} frame"
            )

    @property
    def height_px(self) -> int:
        return self.bottom_px - self.top_px

    @property
    def width_px(self) -> int:
        return self.right_px - self.left_px

    @property
    def share(self) -> float:
        """Fraction of the frame's pixels segmented (MOG2, morphology, contours)."""
        return self.height_px * self.width_px / (self.frame_height_px * self.frame_width_px)

    @property
    def clahe_share(self) -> float:
        """Fraction of the frame's pixels equalised."""
        top, bottom, left, right = self.clahe_px
        return (bottom - top) * (right - left) / (self.frame_height_px * self.frame_width_px)

    @property
    def is_full_frame(self) -> bool:
        return self.share == 1.0

    @property
    def slices(self) -> tuple[slice, slice]:
        """``frame[crop.slices]`` is the crop (a view)."""
        return slice(self.top_px, self.bottom_px), slice(self.left_px, self.right_px)

    @property
    def clahe_slices(self) -> tuple[slice, slice]:
        """``frame[crop.clahe_slices]`` is the part equalised (a view)."""
        top, bottom, left, right = self.clahe_px
        return slice(top, bottom), slice(left, right)

    @property
    def slices_in_clahe(self) -> tuple[slice, slice]:
        """``equalised[crop.slices_in_clahe]`` is the crop, within the equalised part."""
        top, _, left, _ = self.clahe_px
        return (
            slice(self.top_px - top, self.bottom_px - top),
            slice(self.left_px - left, self.right_px - left),
        )


def full_frame(height_px: int, width_px: int, clahe_tiles: int = 8) -> Crop:
    """The whole frame, equalised on a ``clahe_tiles`` x ``clahe_tiles`` grid (the paper's)."""
    return Crop(
        0, height_px, 0, width_px, height_px, width_px,
        (0, height_px, 0, width_px), (clahe_tiles, clahe_tiles),
    )  # fmt: skip


def band_top_depression_rad(camera_height_m: float, max_distance_m: float) -> float | None:
    """Smallest depression below the horizon of any point of a Table 1 target whose nearest
    ground point is at most ``max_distance_m`` ahead, rad; None if a target can reach the
    camera's height (then any row, up to the top of the frame, can hold one)."""
    worst = math.inf
    for size in TABLE1.values():
        top_m = size.height_m[1]
        if top_m >= camera_height_m:
            return None
        reach_m = math.hypot(size.length_m[1], size.width_m[1])
        worst = min(worst, math.atan2(camera_height_m - top_m, max_distance_m + reach_m))
    return worst


def band_top_row_px(camera: CameraModel, max_distance_m: float) -> float:
    """Undistorted row above which no part of a target within range can appear (continuous
    coordinate; ``-inf`` when any row can hold one)."""
    alpha = band_top_depression_rad(camera.height_m, max_distance_m)
    if alpha is None:
        return -math.inf
    return camera.cy_px + camera.fy_px * math.tan(alpha - math.radians(camera.tilt_deg))


def band_bounds_px(camera: CameraModel, max_distance_m: float) -> tuple[int, int, int] | None:
    """``(first row, first column, last column + 1)`` of the pixels that can hold part of a
    target within range, before margins; None if none can (the ground within range is out of view)."""
    v_top = band_top_row_px(camera, max_distance_m)
    w, h = camera.width_px, camera.height_px
    if not camera.has_distortion:
        # pixel row r spans [r - 0.5, r + 0.5]; it holds the band if r + 0.5 > v_top
        first = 0 if v_top == -math.inf else max(0, math.ceil(v_top - 0.5))
        return (first, 0, w) if first < h else None
    step = max(1, math.ceil(w / _BAND_COLUMNS))
    cols = np.unique(np.r_[np.arange(0, w, step), w - 1, math.floor(camera.cx_px)].clip(0, w - 1))
    uu, vv = np.meshgrid(cols.astype(np.float64), np.arange(h, dtype=np.float64))
    v_und = camera.undistort_pixels(np.column_stack([uu.ravel(), vv.ravel()]))[:, 1]
    # a pixel whose undistortion failed (NaN) counts as in the band
    inside = ~(v_und + 0.5 <= v_top).reshape(h, len(cols))
    rows, at = np.nonzero(inside)
    if len(rows) == 0:
        return None
    left = max(0, int(cols[at.min()]) - step + 1)
    right = min(w, int(cols[at.max()]) + step)
    return int(rows.min()), left, right


def morphology_margin_px(open_kernel_px: int, dilate_iterations: int) -> int:
    """Rows (columns) beyond the band the crop needs so a target's region inside it is traced on
    the full frame's mask: growth by the joining dilation, one background row, and the reach of
    erosion, dilation and the joining dilation (see the module docstring)."""
    r = open_kernel_px // 2
    return dilate_iterations * r + 1 + (2 + dilate_iterations) * r


def range_crop(
    camera: CameraModel,
    max_distance_m: float,
    clahe_tiles: int = 8,
    open_kernel_px: int = 3,
    dilate_iterations: int = 1,
    equalise_tiles_only: bool = False,
) -> Crop:
    """The crop of ``camera``'s frame that holds every target within ``max_distance_m``, equalised
    with the whole frame (exactly the full frame's equalisation) or, if ``equalise_tiles_only``,
    on the full frame's CLAHE tiles it needs only (see the module docstring)."""
    h, w = camera.height_px, camera.width_px
    bounds = band_bounds_px(camera, max_distance_m)
    margin = _DISTORTION_MARGIN_PX + morphology_margin_px(open_kernel_px, dilate_iterations)
    # no part of a target within range in view (it would stand below the frame): the bottom rows
    first, left, right = bounds if bounds is not None else (h - 1, 0, w)
    top = max(0, first - margin)
    left, right = max(0, left - margin), min(w, right + margin)
    # a frame OpenCV pads (not a whole number of tiles) is equalised whole too
    if not equalise_tiles_only or h % clahe_tiles or w % clahe_tiles:
        return Crop(top, h, left, right, h, w, (0, h, 0, w), (clahe_tiles, clahe_tiles))
    tile_h, tile_w = h // clahe_tiles, w // clahe_tiles
    first_tile_row, last_tile_row = _tiles_needed(top, h, tile_h, clahe_tiles)
    first_tile_col, last_tile_col = _tiles_needed(left, right, tile_w, clahe_tiles)
    clahe_px = (
        first_tile_row * tile_h,
        (last_tile_row + 1) * tile_h,
        first_tile_col * tile_w,
        (last_tile_col + 1) * tile_w,
    )
    tiles = (last_tile_col - first_tile_col + 1, last_tile_row - first_tile_row + 1)
    return Crop(top, h, left, right, h, w, clahe_px, tiles)


def _tiles_needed(start_px: int, end_px: int, tile_px: int, n_tiles: int) -> tuple[int, int]:
    """First and last of ``n_tiles`` tiles (0-based) whose look-up tables CLAHE interpolates for
    pixels start_px .. end_px - 1: OpenCV puts pixel p between tiles floor(p / tile - 0.5) and
    the next one (clamped to the grid)."""
    first = max(0, math.floor(start_px / tile_px - 0.5))
    last = min(n_tiles - 1, math.floor((end_px - 1) / tile_px - 0.5) + 1)
    return first, last
