"""Regions cut by the frame's edge that may still be measured (``Detector(border_filter=False)``).

Convention: boxes are OpenCV ``(x, y, w, h)`` pixels of the full frame, y down; a box reaching
column 0, row 0, the last column or the last row is cut by that edge. A region cut by the left,
right or top edge still shows its bottom row, so its ground distance (eqs. 2-4); its width (left
or right cut) or height (top cut) is a lower bound. It is kept when it continues a live track
(the track's pooled class decides) or when its visible part fits a target class on its own.
A region cut by the bottom edge has its foot row below the frame: it is nearer than the frame's
bottom row's ground distance and its height is a lower bound; it is kept only when it continues
a live track. A region cut by the band of rows the detector segments (``detector.roi``) stays out.

Design: docs/design/detector-real-footage.md (Regions at the frame's edge)
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from detector.segment import Regions
from detector.tracks.plausibility import APPARENT_SIZES_M, PlausibilityLimits

#: how far outside Table 1's apparent sizes a visible part may measure and still fit a class,
#: share of the bound (the tracks' own size tolerance)
SIZE_TOLERANCE = PlausibilityLimits().size_tolerance


def boxes_overlap(a: Sequence[int], b: Sequence[int]) -> bool:
    """Whether two (x, y, w, h) boxes share a pixel."""
    return a[0] < b[0] + b[2] and b[0] < a[0] + a[2] and a[1] < b[1] + b[3] and b[1] < a[1] + a[3]


def cut_sides(box: Sequence[int], frame_height_px: int, frame_width_px: int) -> tuple[bool, bool, bool]:
    """(width cut: left or right edge, height cut from above: top edge, bottom edge) of an (x, y, w, h) box."""
    x, y, w, h = box
    return x <= 0 or x + w >= frame_width_px, y <= 0, y + h >= frame_height_px


def visible_part_fits(cls: str, width_m: float, height_m: float, width_cut: bool, height_cut: bool) -> bool:
    """Whether a region's visible part (width and height m; a cut one a lower bound) may be a
    ``cls`` by Table 1's apparent sizes (``detector.tracks.plausibility.APPARENT_SIZES_M``): each
    size at most its class's largest, and an uncut one at least its smallest, within ``SIZE_TOLERANCE``."""
    (w_lo, w_hi), (h_lo, h_hi) = APPARENT_SIZES_M[cls]
    tol = SIZE_TOLERANCE
    width_ok = width_m <= w_hi * (1 + tol) and (width_cut or width_m >= w_lo * (1 - tol))
    return width_ok and height_m <= h_hi * (1 + tol) and (height_cut or height_m >= h_lo * (1 - tol))


def keep_cut_regions(regions: Regions, boxes: list, rows: list, edge: list, frame_shape_px: tuple[int, int],
                     live_track_boxes: list, *, classify: Callable[[list], list[list[float]]],
                     class_names: Sequence[str], threshold: float) -> None:
    """Un-flag (set ``edge[i]`` False) the regions cut by the frame's edge that may be measured.

    Parameters
    ----------
    regions : detector.segment.Regions
        The frame's regions (``touches_border``, ``cut_by_crop``).
    boxes : list of (x, y, w, h)
        Their boxes, px.
    rows : list
        Their feature rows (``detector.features.FEATURE_NAMES``: width m, height m, ...; None
        where a region has no ground point).
    edge : list of bool
        Whether each region is dropped for its edge; changed in place.
    frame_shape_px : (int, int)
        The frame's height and width, px.
    live_track_boxes : list of (x, y, w, h)
        The last box of every live track, px.
    classify : callable
        Feature rows -> class probabilities per row, in ``class_names``' order.
    class_names : sequence of str
        The classifier's classes (one is 'noise').
    threshold : float
        P(target) a region's own classification must reach to be kept without a track.
    """
    touches, cut = regions.touches_border.tolist(), regions.cut_by_crop
    cut = [False] * len(touches) if cut is None else cut.tolist()
    alone = []  # side- or top-cut regions on no track: kept if their visible part fits a class
    for i, box in enumerate(boxes):
        if not (edge[i] and touches[i] and not cut[i] and rows[i] is not None):
            continue
        if any(boxes_overlap(box, last) for last in live_track_boxes):
            edge[i] = False  # continues a track: the track decides (bottom-cut ones too)
        elif not cut_sides(box, *frame_shape_px)[2]:
            alone.append(i)
    if not alone:
        return
    noise = list(class_names).index("noise")
    for i, proba in zip(alone, classify([rows[i] for i in alone]), strict=True):
        best = max((c for c in range(len(class_names)) if c != noise), key=lambda c: proba[c])
        width_cut, height_cut, _ = cut_sides(boxes[i], *frame_shape_px)
        if 1.0 - proba[noise] >= threshold and visible_part_fits(class_names[best], rows[i][0], rows[i][1],
                                                                   width_cut, height_cut):
            edge[i] = False
