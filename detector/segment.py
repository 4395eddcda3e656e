"""Moving-region segmentation: the paper's pre-processing and filtering stages (section 3).

One grayscale frame in, the moving regions of that frame out: CLAHE, MOG2 background
subtraction, shadow cut, opening, dilation, external contours, boxes and contour areas, size and
extent filter; on the whole frame or on a ``detector.roi.Crop`` of it (regions touching a crop
edge that is not a frame edge are flagged ``cut_by_crop``).

Conventions: boxes are OpenCV ``boundingRect`` tuples ``(x, y, w, h)`` in pixels of the full
frame (pixel centres on integers, so the box covers columns x .. x + w - 1); contour areas are
``cv2.contourArea``'s (Green's theorem over the vertices: a filled w x h rectangle has area
(w-1)(h-1)).

Design: docs/design/modules.md (Segmentation)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from detector import contours as contour_sets
from detector.clahe import CropCLAHE
from detector.regions import Regions, few_regions
from detector.roi import Crop, full_frame

__all__ = ["DEFAULT_HISTORY_S", "REFERENCE_FPS", "Regions", "Segmenter", "SegmenterParams"]

# the regions of a frame where nothing moved, shared: zero-size arrays hold nothing to change
_NO_BOXES = np.zeros((0, 4), np.int32)
_NO_AREAS = np.zeros(0, np.float64)
_NO_FLAGS = np.zeros(0, bool)
#: Frame rate the default history was set for (``CameraModel``'s default), frames/s.
REFERENCE_FPS = 15.0
#: MOG2's history, s: the paper implementation's 500 frames at ``REFERENCE_FPS``.
DEFAULT_HISTORY_S = 500 / REFERENCE_FPS
# MOG2 writes shadows as this value (its default; the shadow cut is defined against it)
_MOG2_SHADOW_VALUE = 127


@dataclass(frozen=True)
class SegmenterParams:
    """Segmentation settings; defaults are the paper implementation's values.

    ``clahe_tile_px`` is OpenCV's ``tileGridSize`` on the full frame: the number of
    tiles per image side (8 -> an 8 x 8 grid, i.e. 40 x 30 px tiles on a 320 x 240
    frame); a crop is equalised on the full frame's tiles that it needs.
    ``mog2_history_s`` is MOG2's history in seconds (frames = seconds x the camera's
    frames/s). ``min_area_fraction`` is a fraction of the frame area; ``min_extent``
    is contour area / bounding-box area. ``learning_rate`` is MOG2's (-1: automatic).
    """

    clahe_clip_limit: float = 3.0
    clahe_tile_px: int = 8
    mog2_history_s: float = DEFAULT_HISTORY_S
    mog2_var_threshold: float = 16.0
    detect_shadows: bool = True
    shadow_cut: int = 170
    open_kernel_px: int = 3
    dilate_iterations: int = 1
    min_area_fraction: float = 0.001
    min_extent: float = 0.2
    learning_rate: float = -1.0

    def __post_init__(self) -> None:
        int_at_least = "an integer >= {}".format
        checks = (
            ("clahe_clip_limit", self.clahe_clip_limit > 0, "> 0"),
            (
                "clahe_tile_px",
                _is_int(self.clahe_tile_px) and self.clahe_tile_px >= 1,
                int_at_least(1),
            ),
            ("mog2_history_s", self.mog2_history_s > 0, "> 0 s"),
            ("mog2_var_threshold", self.mog2_var_threshold > 0, "> 0"),
            (
                "shadow_cut",
                _is_int(self.shadow_cut) and 0 <= self.shadow_cut <= 254,
                "an integer in 0..254",
            ),
            (
                "open_kernel_px",
                _is_int(self.open_kernel_px) and self.open_kernel_px >= 1,
                int_at_least(1),
            ),
            (
                "dilate_iterations",
                _is_int(self.dilate_iterations) and self.dilate_iterations >= 0,
                int_at_least(0),
            ),
            ("min_area_fraction", 0.0 <= self.min_area_fraction < 1.0, "in [0, 1)"),
            ("min_extent", 0.0 <= self.min_extent <= 1.0, "in [0, 1]"),
            (
                "learning_rate",
                self.learning_rate == -1.0 or 0.0 <= self.learning_rate <= 1.0,
                "-1 (automatic) or in [0, 1]",
            ),
        )
        for name, ok, valid in checks:
            if not ok:
                raise ValueError(
                    f"SegmenterParams.{name} must be {valid}, got {getattr(self, name)!r}"
                )

    def history_frames(self, fps: float) -> int:
        """MOG2's history in frames for a camera taking ``fps`` frames/s (at least 1)."""
        return max(1, round(self.mog2_history_s * fps))


def _is_int(value: object) -> bool:
    return isinstance(value, int | np.integer) and not isinstance(value, bool)


class Segmenter:
    """Stateful per-camera segmenter: owns the MOG2 background model and the frame buffers.

    ``fps``: the camera's frame rate, frames/s, which turns the history in seconds
    into frames. ``crop``: work on this part of frames of its frame size only
    (``detector.roi.range_crop``); None: on whole frames of any size.
    """

    def __init__(
        self,
        params: SegmenterParams = SegmenterParams(),
        fps: float = REFERENCE_FPS,
        crop: Crop | None = None,
    ) -> None:
        if not isinstance(params, SegmenterParams):
            raise TypeError(
                f"Segmenter params must be a SegmenterParams, got {type(params).__name__}"
            )
        if not (isinstance(fps, int | float) and fps > 0):
            raise ValueError(f"Segmenter fps must be > 0 frames/s, got {fps!r}")
        if crop is not None and not isinstance(crop, Crop):
            raise TypeError(
                f"Segmenter crop must be a detector.roi.Crop, got {type(crop).__name__}"
            )
        self.params = params
        self.fps = float(fps)
        self.history_frames = params.history_frames(self.fps)
        self._kernel = cv2.getStructuringElement(
            cv2.MORPH_ELLIPSE, (params.open_kernel_px, params.open_kernel_px)
        )
        # MOG2 writes shadows as the cut leaves them: no threshold pass
        self._shadow_value = 255 if _MOG2_SHADOW_VALUE > params.shadow_cut else 0
        self.crop = crop
        self._frame_shape: tuple[int, int] | None = None
        if crop is not None:
            self._use_crop(crop)
        self._mog2: cv2.BackgroundSubtractorMOG2
        self.reset()

    def _use_crop(self, crop: Crop) -> None:
        """Buffers, CLAHE grid and edge limits for frames of ``crop``'s frame size."""
        self._frame_shape = (crop.frame_height_px, crop.frame_width_px)
        self._clahe_part = crop.clahe_slices
        self._clahe = cv2.createCLAHE(
            clipLimit=self.params.clahe_clip_limit, tileGridSize=crop.clahe_tiles
        )
        top, bottom, left, right = crop.clahe_px
        # the whole frame's equalisation: the crop's values only, computed on the crop
        self._crop_clahe = None
        if (top, bottom, left, right) == (0, crop.frame_height_px, 0, crop.frame_width_px):
            self._crop_clahe = CropCLAHE(
                self.params.clahe_clip_limit, self.params.clahe_tile_px, (bottom, right),
                (crop.top_px, crop.bottom_px), (crop.left_px, crop.right_px),
            )  # fmt: skip
            self._equalised = self._equalised_crop = self._crop_clahe.out
        else:
            self._equalised = np.empty((bottom - top, right - left), np.uint8)
            self._equalised_crop = self._equalised[crop.slices_in_clahe]
        self._mask = np.zeros(self._frame_shape, np.uint8)
        self._fg = self._mask[crop.slices]
        self._frame_px = crop.frame_height_px * crop.frame_width_px
        self._crop_px = crop.height_px * crop.width_px
        self._min_area_px = self.params.min_area_fraction * self._frame_px
        # a region is cut where it reaches a crop edge; by the frame where that edge is the frame's
        self._lo = (crop.left_px, crop.top_px)
        self._hi = (crop.right_px, crop.bottom_px)
        self._cropped = not crop.is_full_frame
        # (left, top, right, bottom): whether that edge of the crop is the frame's
        self._frame_edges = (
            crop.left_px == 0, crop.top_px == 0,
            crop.right_px == crop.frame_width_px, crop.bottom_px == crop.frame_height_px,
        )  # fmt: skip
        self._lo_is_frame = np.array(self._frame_edges[:2])
        self._hi_is_frame = np.array(self._frame_edges[2:])

    @property
    def clahe_histogram_share(self) -> float:
        """Fraction of the frame's pixels whose CLAHE histograms each frame takes."""
        crop_clahe = getattr(self, "_crop_clahe", None)  # none before a crop's first frame
        return 1.0 if crop_clahe is None else crop_clahe.histogram_share

    def automatic_learning_rate(self, frames_before: int) -> float:
        """The rate MOG2 picks itself for a frame with ``frames_before`` frames before it since the
        last reset: 1 (the first frame becomes the background), then 1 / min(2 n, history) with n
        counting this frame."""
        if frames_before <= 0:
            return 1.0
        return 1.0 / min(2 * (frames_before + 1), self.history_frames)

    def reset(self) -> None:
        """Forget the background: the next frame becomes the new background.

        Needed when the lamp in view switches and the whole scene changes
        brightness at once, which MOG2 would otherwise report as one huge
        foreground region for hundreds of frames.
        """
        p = self.params
        self._mog2 = cv2.createBackgroundSubtractorMOG2(
            history=self.history_frames,
            varThreshold=p.mog2_var_threshold,
            detectShadows=p.detect_shadows,
        )
        self._mog2.setShadowValue(self._shadow_value)

    def brightness_dn(self, box_px: Sequence[int]) -> tuple[float, float] | None:
        """(last frame, background model) mean equalised brightness over the foreground pixels of
        ``box_px`` (x, y, w, h, frame pixels), DN; None where it holds none. A light spot on the
        ground is brighter than the ground was, and brighter than the object casting it. Reads
        the model's background image (a whole-crop computation): for the few regions that ask."""
        left, top = self._lo
        x, y, w, h = box_px
        x0, y0 = max(x - left, 0), max(y - top, 0)
        x1, y1 = x - left + w, y - top + h
        fg = self._fg[y0:y1, x0:x1] > 0
        background = self._mog2.getBackgroundImage() if fg.any() else None
        if background is None:
            return None
        now = self._equalised_crop[y0:y1, x0:x1][fg].astype(np.float64)
        return float(now.mean()), float(background[y0:y1, x0:x1][fg].mean())

    def apply(self, gray: np.ndarray, learning_rate: float | None = None) -> Regions:
        """Segment one uint8 (H, W) frame and update the background model.

        ``learning_rate`` overrides the parameters' for this frame: a caller that judges only
        some of a camera's frames passes the rate the model would have had on every frame.
        """
        if not isinstance(gray, np.ndarray) or gray.dtype != np.uint8 or gray.ndim != 2:
            got = (
                f"{gray.dtype} array of shape {gray.shape}"
                if isinstance(gray, np.ndarray)
                else type(gray).__name__
            )
            raise ValueError(f"Segmenter.apply needs a grayscale uint8 (H, W) frame, got {got}")
        if gray.shape != self._frame_shape:
            if self.crop is not None:
                raise ValueError(
                    f"Segmenter.apply: this segmenter's crop is of {self._frame_shape} frames, "
                    f"got a frame of shape {gray.shape}"
                )
            self._use_crop(full_frame(*gray.shape, self.params.clahe_tile_px))
        p, fg = self.params, self._fg
        if self._crop_clahe is not None:
            self._crop_clahe.apply(gray)
        else:
            self._clahe.apply(gray[self._clahe_part], dst=self._equalised)
        rate = p.learning_rate if learning_rate is None else learning_rate
        self._mog2.apply(self._equalised_crop, fgmask=fg, learningRate=rate)
        # nothing moved: no morphology or contours to run (hasNonZero stops at the first set pixel:
        # 1-2 us where counting them all takes 3-4 us, measured on the suburban band)
        if not cv2.hasNonZero(fg):
            return Regions(_NO_BOXES, _NO_AREAS, [], _NO_FLAGS, 0.0, self._mask, _NO_FLAGS)
        # one call for the opening (OpenCV's erosion then dilation): every call after MOG2 has
        # walked the caches costs several microseconds (measured: ~1 % of the detector's frame)
        cv2.morphologyEx(fg, cv2.MORPH_OPEN, self._kernel, dst=fg)
        foreground_fraction = cv2.countNonZero(fg) / self._crop_px
        if p.dilate_iterations > 0:
            cv2.dilate(fg, self._kernel, dst=fg, iterations=p.dilate_iterations)
        contours, _ = cv2.findContours(
            fg, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE, offset=self._lo
        )
        if len(contours) > contour_sets.FEW_CONTOURS:
            kept, boxes, areas = self._filter_many(contours)
            touches, cut = self._edges(boxes)
            return Regions(boxes, areas, kept, touches, foreground_fraction, self._mask, cut)
        return self._filter_few(contours, foreground_fraction)

    def _filter_few(self, contours, foreground_fraction: float) -> Regions:
        """The regions of a frame's few contours: plain Python over OpenCV's per-contour calls,
        areas first and boxes only for the survivors (most are specks); the edge flags as
        ``_edges`` gives them, in Python too; numpy only for the results."""
        min_area_px, min_extent = self._min_area_px, self.params.min_extent
        (left, top), (right, bottom) = self._lo, self._hi
        frame_edges = self._frame_edges
        kept, box_rows, area_rows, touch_rows, cut_rows = [], [], [], [], []
        for contour in contours:
            area = cv2.contourArea(contour)
            if area < min_area_px:
                continue
            x, y, w, h = cv2.boundingRect(contour)
            if area < min_extent * (w * h):
                continue
            kept.append(contour)
            box_rows.append([x, y, w, h])
            area_rows.append(area)
            if x > left and y > top and x + w < right and y + h < bottom:  # the usual region
                touch_rows.append(False)
                cut_rows.append(False)
                continue
            reached = (x <= left, y <= top, x + w >= right, y + h >= bottom)
            touch_rows.append(any(r and f for r, f in zip(reached, frame_edges, strict=True)))
            cut_rows.append(any(r and not f for r, f in zip(reached, frame_edges, strict=True)))
        if not kept:  # the usual frame: nothing moved (zero-size arrays cannot be mutated)
            return Regions(
                _NO_BOXES, _NO_AREAS, kept, _NO_FLAGS, foreground_fraction, self._mask, _NO_FLAGS
            )
        return few_regions(kept, box_rows, area_rows, touch_rows, cut_rows, foreground_fraction, self._mask)

    def _filter_many(self, contours) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
        """Contours passing the size and extent limits, their boxes and areas, vectorised over all
        vertices for the many specks of a noisy frame."""
        idx, boxes, areas = contour_sets.large_enough(contours, self._min_area_px)
        dense = areas >= self.params.min_extent * (boxes[:, 2].astype(np.float64) * boxes[:, 3])
        idx, boxes, areas = idx[dense], boxes[dense], areas[dense]
        return [contours[i] for i in idx], boxes, areas

    def _edges(self, boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(touches the frame's border, touches a crop edge that is not the frame's), (N,) each."""
        low = boxes[:, :2] <= self._lo
        high = boxes[:, :2] + boxes[:, 2:] >= self._hi
        frame_low = low & self._lo_is_frame
        frame_high = high & self._hi_is_frame
        touches = np.any(frame_low | frame_high, axis=1)
        return touches, np.any((low & ~frame_low) | (high & ~frame_high), axis=1)
