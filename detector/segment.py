"""Moving-region segmentation: the paper's pre-processing and filtering stages (section 3).

One grayscale frame in, the moving regions of that frame out:

    CLAHE -> MOG2 background subtraction -> shadow cut -> opening -> dilation
    -> external contours -> bounding boxes and contour areas -> size/extent filter

Conventions: boxes are OpenCV ``boundingRect`` tuples ``(x, y, w, h)`` in
pixels (pixel centres on integers, so the box covers columns x .. x + w - 1);
contour areas come from Green's theorem over the contour vertices, exactly what
``cv2.contourArea`` returns (a filled w x h rectangle has area (w-1)(h-1)).

The reference values (CLAHE clip limit 3 on an 8 x 8 tile grid, MOG2 variance
threshold 16 with shadow detection, shadows cut at 170, a 3 x 3 elliptic
opening, one extra dilation) are those of the paper's published implementation.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

# below this many contours a Python loop over cv2 calls beats the vectorised path (measured: 40 contours ~ equal)
_FEW_CONTOURS = 32
# the regions of a frame where nothing moved, shared: zero-size arrays hold nothing to change
_NO_BOXES = np.zeros((0, 4), np.int32)
_NO_AREAS = np.zeros(0, np.float64)
_NO_FLAGS = np.zeros(0, bool)


@dataclass(frozen=True)
class SegmenterParams:
    """Segmentation settings; defaults are the paper implementation's values.

    ``clahe_tile_px`` is OpenCV's ``tileGridSize``: the number of tiles per image
    side (8 -> an 8 x 8 grid, i.e. 40 x 30 px tiles on a 320 x 240 frame).
    ``min_area_fraction`` is a fraction of the frame area; ``min_extent`` is
    contour area / bounding-box area. ``learning_rate`` is MOG2's (-1: automatic).
    """

    clahe_clip_limit: float = 3.0
    clahe_tile_px: int = 8
    mog2_history: int = 500
    mog2_var_threshold: float = 16.0
    detect_shadows: bool = True
    shadow_cut: int = 170
    open_kernel_px: int = 3
    dilate_iterations: int = 1
    min_area_fraction: float = 0.001
    min_extent: float = 0.2
    learning_rate: float = -1.0

    def __post_init__(self) -> None:
        checks = (
            ("clahe_clip_limit", self.clahe_clip_limit > 0, "> 0"),
            (
                "clahe_tile_px",
                _is_int(self.clahe_tile_px) and self.clahe_tile_px >= 1,
                "an integer >= 1",
            ),
            (
                "mog2_history",
                _is_int(self.mog2_history) and self.mog2_history >= 1,
                "an integer >= 1",
            ),
            ("mog2_var_threshold", self.mog2_var_threshold > 0, "> 0"),
            (
                "shadow_cut",
                _is_int(self.shadow_cut) and 0 <= self.shadow_cut <= 254,
                "an integer in 0..254",
            ),
            (
                "open_kernel_px",
                _is_int(self.open_kernel_px) and self.open_kernel_px >= 1,
                "an integer >= 1",
            ),
            (
                "dilate_iterations",
                _is_int(self.dilate_iterations) and self.dilate_iterations >= 0,
                "an integer >= 0",
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


def _is_int(value: object) -> bool:
    return isinstance(value, int | np.integer) and not isinstance(value, bool)


@dataclass(frozen=True)
class Regions:
    """The moving regions of one frame.

    Regions below the size or extent limits are gone; regions touching the frame
    border are kept but flagged in ``touches_border`` (the detector skips them:
    their shape is cut by the border). ``foreground_fraction`` counts foreground
    pixels after the shadow cut and the opening, before the joining dilation.
    ``mask`` (uint8, 0 or 255) is the final mask the contours were traced on.
    """

    boxes_px: np.ndarray  # (N, 4) int32 x, y, w, h
    areas_px: np.ndarray  # (N,) float64, Green's-theorem contour areas
    contours: list[np.ndarray]  # N OpenCV contours, (K, 1, 2) int32
    touches_border: np.ndarray  # (N,) bool
    foreground_fraction: float
    mask: np.ndarray = field(repr=False)  # (H, W) uint8

    def __len__(self) -> int:
        return len(self.boxes_px)

    @property
    def extents(self) -> np.ndarray:
        """Contour area / bounding-box area, (N,)."""
        return self.areas_px / np.maximum(self.boxes_px[:, 2] * self.boxes_px[:, 3], 1)

    @classmethod
    def empty(cls, height_px: int, width_px: int) -> Regions:
        return cls(
            boxes_px=np.zeros((0, 4), np.int32),
            areas_px=np.zeros(0),
            contours=[],
            touches_border=np.zeros(0, bool),
            foreground_fraction=0.0,
            mask=np.zeros((height_px, width_px), np.uint8),
        )


class Segmenter:
    """Stateful per-camera segmenter: owns the MOG2 background model."""

    def __init__(self, params: SegmenterParams = SegmenterParams()) -> None:
        if not isinstance(params, SegmenterParams):
            raise TypeError(
                f"Segmenter params must be a SegmenterParams, got {type(params).__name__}"
            )
        self.params = params
        self._clahe = cv2.createCLAHE(
            clipLimit=params.clahe_clip_limit,
            tileGridSize=(params.clahe_tile_px, params.clahe_tile_px),
        )
        self._kernel = cv2.getStructuringElement(
            cv2.MORPH_ELLIPSE, (params.open_kernel_px, params.open_kernel_px)
        )
        self._mog2: cv2.BackgroundSubtractorMOG2
        self.reset()

    def automatic_learning_rate(self, frames_before: int) -> float:
        """The rate MOG2 picks itself for a frame with ``frames_before`` frames before it since the
        last reset: 1 (the first frame becomes the background), then 1 / min(2 n, history) with n
        counting this frame."""
        if frames_before <= 0:
            return 1.0
        return 1.0 / min(2 * (frames_before + 1), self.params.mog2_history)

    def reset(self) -> None:
        """Forget the background: the next frame becomes the new background.

        Needed when the lamp in view switches and the whole scene changes
        brightness at once, which MOG2 would otherwise report as one huge
        foreground region for hundreds of frames.
        """
        p = self.params
        self._mog2 = cv2.createBackgroundSubtractorMOG2(
            history=p.mog2_history,
            varThreshold=p.mog2_var_threshold,
            detectShadows=p.detect_shadows,
        )

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
        p = self.params
        equalised = self._clahe.apply(gray)
        rate = p.learning_rate if learning_rate is None else learning_rate
        fg = self._mog2.apply(equalised, learningRate=rate)
        # shadows are written as 127; the cut turns them (and nothing brighter) into background
        cv2.threshold(fg, p.shadow_cut, 255, cv2.THRESH_BINARY, dst=fg)
        cv2.morphologyEx(fg, cv2.MORPH_OPEN, self._kernel, dst=fg)
        frame_px = gray.shape[0] * gray.shape[1]
        foreground_fraction = cv2.countNonZero(fg) / frame_px
        if p.dilate_iterations > 0:
            cv2.dilate(fg, self._kernel, dst=fg, iterations=p.dilate_iterations)
        contours, _ = cv2.findContours(fg, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        height_px, width_px = gray.shape
        min_area_px = p.min_area_fraction * frame_px
        if len(contours) > _FEW_CONTOURS:
            idx, boxes, areas = _large_enough(contours, min_area_px)
            dense = areas >= p.min_extent * (boxes[:, 2].astype(np.float64) * boxes[:, 3])
            idx, boxes, areas = idx[dense], boxes[dense], areas[dense]
            touches = np.any(
                (boxes[:, :2] <= 0) | (boxes[:, :2] + boxes[:, 2:] >= (width_px, height_px)),
                axis=1,
            )
            kept = [contours[i] for i in idx]
        else:
            # few contours: plain Python over OpenCV's per-contour calls, areas first and
            # boxes only for the survivors (most are specks); numpy only for the results
            kept, box_rows, area_rows, touch_rows = [], [], [], []
            for contour in contours:
                area = cv2.contourArea(contour)
                if area < min_area_px:
                    continue
                x, y, w, h = cv2.boundingRect(contour)
                if area < p.min_extent * (w * h):
                    continue
                kept.append(contour)
                box_rows.append((x, y, w, h))
                area_rows.append(area)
                touch_rows.append(x <= 0 or y <= 0 or x + w >= width_px or y + h >= height_px)
            if not kept:  # the usual frame: nothing moved (zero-size arrays cannot be mutated)
                return Regions(_NO_BOXES, _NO_AREAS, kept, _NO_FLAGS, foreground_fraction, fg)
            boxes = np.array(box_rows, np.int32).reshape(-1, 4)
            areas = np.array(area_rows, np.float64)
            touches = np.array(touch_rows, bool)
        return Regions(
            boxes_px=boxes,
            areas_px=areas,
            contours=kept,
            touches_border=touches,
            foreground_fraction=foreground_fraction,
            mask=fg,
        )


def _large_enough(contours, min_area_px: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Indices, boxes and areas of the (many) contours with Green's-theorem area >= min_area_px."""
    boxes, areas = contour_boxes_and_areas(contours)
    idx = np.flatnonzero(areas >= min_area_px)
    return idx, boxes[idx], areas[idx]


def contour_boxes_and_areas(
    contours: list[np.ndarray] | tuple[np.ndarray, ...],
) -> tuple[np.ndarray, np.ndarray]:
    """Bounding boxes (N, 4) int32 and Green's-theorem areas (N,) of N OpenCV contours.

    Equal to ``cv2.boundingRect`` and ``cv2.contourArea`` per contour, but done
    in a handful of numpy calls over all vertices at once once there are many
    (a frame of sensor noise can hold hundreds of specks); for a few contours
    OpenCV's own per-contour calls are cheaper than numpy's call overhead.
    """
    if len(contours) <= _FEW_CONTOURS:
        boxes = np.array([cv2.boundingRect(c) for c in contours], np.int32).reshape(-1, 4)
        return boxes, np.array([cv2.contourArea(c) for c in contours], np.float64)
    counts = np.fromiter((len(c) for c in contours), dtype=np.intp, count=len(contours))
    pts = np.concatenate(contours).reshape(-1, 2).astype(np.int64)
    starts = np.zeros(len(counts), dtype=np.intp)
    np.cumsum(counts[:-1], out=starts[1:])
    lo = np.minimum.reduceat(pts, starts, axis=0)
    hi = np.maximum.reduceat(pts, starts, axis=0)
    boxes = np.column_stack([lo, hi - lo + 1]).astype(np.int32)
    # shoelace: each vertex pairs with the next one of its own contour (wrapping)
    nxt = np.arange(1, len(pts) + 1)
    nxt[starts + counts - 1] = starts
    cross = pts[:, 0] * pts[nxt, 1] - pts[nxt, 0] * pts[:, 1]
    areas = 0.5 * np.abs(np.add.reduceat(cross, starts).astype(np.float64))
    return boxes, areas
