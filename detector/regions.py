"""The moving regions of one frame (``Regions``), as the segmenter (``detector.segment``) gives them.

Conventions: boxes are OpenCV ``boundingRect`` tuples ``(x, y, w, h)`` in pixels of the full
frame; contour areas are Green's-theorem areas (``cv2.contourArea``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from operator import or_

import numpy as np


@dataclass(frozen=True)
class Regions:
    """The moving regions of one frame, in full-frame pixels.

    Regions below the size or extent limits are gone; regions touching the frame
    border are kept but flagged in ``touches_border`` (the detector skips them:
    their shape is cut by the border); regions touching an edge of the crop the
    segmenter works on, where it is not the frame's edge, are flagged in
    ``cut_by_crop`` (None: no region is). ``foreground_fraction`` is the share of
    the processed pixels (the crop's) that are foreground after the shadow cut and
    the opening, before the joining dilation. ``mask`` (uint8, 0 or 255, the full
    frame's shape; 0 outside the crop) is the final mask the contours were traced
    on: the segmenter's buffer, rewritten by its next frame (copy it to keep it).
    """

    boxes_px: np.ndarray  # (N, 4) int32 x, y, w, h
    areas_px: np.ndarray  # (N,) float64, Green's-theorem contour areas
    contours: list[np.ndarray]  # N OpenCV contours, (K, 1, 2) int32
    touches_border: np.ndarray  # (N,) bool
    foreground_fraction: float
    mask: np.ndarray = field(repr=False)  # (H, W) uint8
    cut_by_crop: np.ndarray | None = None  # (N,) bool
    #: (boxes [x, y, w, h], areas, unusable) as Python lists, when the segmenter has them: the
    #: detector's per-frame path reads these rather than converting the arrays (never mutate)
    lists: tuple[list, list, list] | None = field(default=None, repr=False, compare=False)

    def __len__(self) -> int:
        return len(self.boxes_px)

    @property
    def extents(self) -> np.ndarray:
        """Contour area / bounding-box area, (N,)."""
        return self.areas_px / np.maximum(self.boxes_px[:, 2] * self.boxes_px[:, 3], 1)

    @property
    def unusable(self) -> np.ndarray:
        """(N,) bool: regions whose shape is cut, by the frame's border or by the crop."""
        if self.cut_by_crop is None:
            return self.touches_border
        return self.touches_border | self.cut_by_crop

    @classmethod
    def empty(cls, height_px: int, width_px: int) -> Regions:
        return cls(
            boxes_px=np.zeros((0, 4), np.int32),
            areas_px=np.zeros(0),
            contours=[],
            touches_border=np.zeros(0, bool),
            foreground_fraction=0.0,
            mask=np.zeros((height_px, width_px), np.uint8),
            cut_by_crop=np.zeros(0, bool),
        )


class _ListedRegions(Regions):
    """``Regions`` of a frame's few contours, held as the Python lists the segmenter built them in;
    the arrays are made from the lists on first use (then kept: each is one array, as a
    ``Regions``' field). Why: the detector reads only the lists and the contours, and four small
    arrays and the frozen dataclass's __init__ cost tens of microseconds a frame after MOG2 has
    walked the caches (measured: the bench's detector 2-3 % faster without them)."""

    def __len__(self) -> int:
        return len(self.contours)

    def _array(self, name: str, values: list, dtype: type, shape: tuple = (-1,)) -> np.ndarray:
        cache = self.__dict__
        if name not in cache:
            cache[name] = np.array(values, dtype).reshape(shape)
        return cache[name]

    @property
    def boxes_px(self) -> np.ndarray:  # type: ignore[override]
        return self._array("_boxes_px", self.lists[0], np.int32, (-1, 4))

    @property
    def areas_px(self) -> np.ndarray:  # type: ignore[override]
        return self._array("_areas_px", self.lists[1], np.float64)

    @property
    def touches_border(self) -> np.ndarray:  # type: ignore[override]
        return self._array("_touches_border", self.__dict__["_touch_rows"], bool)

    @property
    def cut_by_crop(self) -> np.ndarray:  # type: ignore[override]
        return self._array("_cut_by_crop", self.__dict__["_cut_rows"], bool)


def few_regions(
    contours: list, box_rows: list, area_rows: list, touch_rows: list, cut_rows: list,
    foreground_fraction: float, mask: np.ndarray,
) -> Regions:  # fmt: skip
    """``Regions`` of (at least one) contours from their boxes [x, y, w, h], areas and edge flags
    as lists: the detector's per-frame path (``Regions.lists``) reads them as they are."""
    regions = object.__new__(_ListedRegions)
    regions.__dict__.update(
        contours=contours, foreground_fraction=foreground_fraction, mask=mask,
        lists=(box_rows, area_rows, list(map(or_, touch_rows, cut_rows))),  # bools: or_ is 'or'
        _touch_rows=touch_rows, _cut_rows=cut_rows,
    )  # fmt: skip
    return regions
