"""Regions cut by the frame's edge that may still be measured: those continuing a track.

Convention: boxes are OpenCV ``(x, y, w, h)`` pixels of the full frame, y down. A region cut by
the left, right or top edge still shows its bottom row, so its ground distance; its width or
height is then a lower bound. A region cut by the bottom edge (feet unseen) or by the band of
rows the detector segments (``detector.roi``) has no trustworthy distance and stays out.
"""

from __future__ import annotations

from collections.abc import Sequence

from detector.segment import Regions


def boxes_overlap(a: Sequence[int], b: Sequence[int]) -> bool:
    """Whether two (x, y, w, h) boxes share a pixel."""
    return a[0] < b[0] + b[2] and b[0] < a[0] + a[2] and a[1] < b[1] + b[3] and b[1] < a[1] + a[3]


def keep_side_cut_continuing_tracks(regions: Regions, boxes: list, edge: list, frame_height_px: int,
                                    live_track_boxes: list) -> None:
    """Un-flag (set ``edge[i]`` False) each region cut only by the frame's left, right or top edge
    whose box overlaps a live track's last box (``live_track_boxes``, px).

    Parameters
    ----------
    regions : detector.segment.Regions
        The frame's regions (``touches_border``, ``cut_by_crop``).
    boxes : list of (x, y, w, h)
        Their boxes, px.
    edge : list of bool
        Whether each region is dropped for its edge; changed in place.
    frame_height_px : int
        The frame's height, px (a box reaching it is cut by the bottom edge).
    live_track_boxes : list of (x, y, w, h)
        The last box of every live track, px.
    """
    touches, cut = regions.touches_border.tolist(), regions.cut_by_crop
    cut = [False] * len(touches) if cut is None else cut.tolist()
    for i, box in enumerate(boxes):
        if edge[i] and touches[i] and not cut[i] and box[1] + box[3] < frame_height_px and any(
                boxes_overlap(box, last) for last in live_track_boxes):  # fmt: skip
            edge[i] = False
