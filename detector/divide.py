"""Region division (paper section 5.2): cut an object away from its own light spot.

At night a cyclist's or car's headlight, or a pedestrian's flashlight, throws
a bright spot on the ground next to the object, and background subtraction
joins the two into one region. Its features then describe neither: the
bounding box is wide and its bottom is the spot's, so the distance, width and
height are all wrong. Following the paper, such a region is divided using its
vertical and horizontal mask histograms and the criteria extent, height to
width ratio and estimated contour area, and the features are computed again
for the object part.

Candidates are regions of low extent (contour area / box area) or of an
estimated area larger than any Table 1 object. Their masks are split by the
pixel-only tests of ``detector.split`` (which also holds the thresholds,
``DivisionParams``, and the evidence for them). The division stands only if,
measured in metres by ``region_features``, the spot part is flat (height /
width below ``max_spot_height_to_width``) and the object part is more upright
and more compact (higher extent) than the whole. And only where a light spot is there: given
``lit`` (the detector's, from ``Segmenter.brightness_dn``: the spot part at least
``MIN_SPOT_BRIGHTENING_DN`` brighter than the ground was and than the object part), a spot
part that is no light on the ground (a day car's body under its roof, a shadow) divides nothing.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from detector.camera import CameraModel
from detector.features import RegionGeometry
from detector.split import DivisionParams
from detector.split_compiled import split_at_widening, split_object_and_spot

# DivisionParams is re-exported: it is the parameter of divide_rows and divide_regions
__all__ = ["MIN_SPOT_BRIGHTENING_DN", "Division", "DivisionParams", "divide_regions", "divide_rows"]

#: a light spot is brighter, on average over its foreground pixels (equalised DN of 255), by at
#: least this much than the background model there and than the object part
MIN_SPOT_BRIGHTENING_DN = 12.0

# frozen, so one shared default instance is safe
_DEFAULT_PARAMS = DivisionParams()


@dataclass(frozen=True)
class Division:
    """Regions after division, aligned row by row.

    ``divided`` marks rows that are now the object part of a divided region. ``spot_boxes_px``
    are the light-spot parts cut off (not classified: a part just shown to be
    flat on the ground is no target).
    """

    boxes_px: np.ndarray  # (M, 4) int32
    areas_px: np.ndarray  # (M,)
    features: np.ndarray  # (M, 6)
    valid: np.ndarray  # (M,) bool
    divided: np.ndarray  # (M,) bool
    spot_boxes_px: np.ndarray  # (S, 4) int32


# tried in this order on a candidate region; the first split that passes the metric criteria stands
# with the names of the DivisionParams fields bounding the spot's height / width (m) and the
# object's height / width (m; None: the object must be more upright than the whole region);
# compiled (``detector.split_compiled``: ``detector.split``'s masks, one call instead of ~50)
SPLITTERS = (
    (split_object_and_spot, "max_spot_height_to_width", None),
    (split_at_widening, "max_beam_height_to_width", "min_beam_object_height_to_width"),
)


def _part_box_and_area(part: np.ndarray, x0: int, y0: int) -> tuple[list[int], float] | None:
    """Frame box [x, y, w, h] and Green's-theorem area of a part mask cut from a box at (x0, y0).

    The box is the mask's own (``cv2.boundingRect`` of its set pixels): the union of its external
    contours' boxes, as every set pixel lies within one of them and each contour's extreme points
    are set pixels (one call rather than one per contour; tests/detector/test_split_compiled.py).
    """
    mask = part.view(np.uint8)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    if not contours:
        return None
    left, top, width, height = cv2.boundingRect(mask)
    area = sum(cv2.contourArea(c) for c in contours)
    return [x0 + left, y0 + top, width, height], float(area)


def _ratio(num: float, den: float) -> float:
    """num / den with numpy's float semantics at den == 0 (inf, or NaN for 0 / 0)."""
    if den:
        return num / den
    return math.copysign(math.inf, num) if num else math.nan


def _accept(
    geometry: RegionGeometry,
    parts: tuple[np.ndarray, np.ndarray] | None,
    x: int,
    y: int,
    extent: float,
    row: list[float],
    max_spot_height_to_width: float,
    min_object_height_to_width: float | None,
) -> tuple[tuple[list[int], float], list[int], list[float]] | None:
    """(object box and area, spot box, object feature row) if a split meets the metric criteria.

    The object must be more upright than the whole region, or, if ``min_object_height_to_width``
    is given, at least that upright.
    """
    if parts is None:
        return None
    body = _part_box_and_area(parts[0], x, y)
    spot = _part_box_and_area(parts[1], x, y)
    if body is None or spot is None:
        return None
    body_row, spot_row = geometry.rows([body[0], spot[0]], [body[1], spot[1]])
    if body_row is None or spot_row is None:
        return None
    body_extent = body[1] / max(body[0][2] * body[0][3], 1)
    if (
        spot_row[1] > max_spot_height_to_width * spot_row[0]
        or body_extent <= extent
        or _ratio(body_row[1], body_row[0])
        <= (
            _ratio(row[1], row[0])
            if min_object_height_to_width is None
            else min_object_height_to_width
        )
    ):
        return None
    return body, spot[0], body_row


def divide_rows(
    geometry: RegionGeometry,
    contours: Sequence[np.ndarray],
    boxes_px: list[list[int]],
    areas_px: list[float],
    rows: list[list[float] | None],
    params: DivisionParams = _DEFAULT_PARAMS,
    beyond_m: float = math.inf,
    lit: Callable[[list[int], list[int]], bool] | None = None,
) -> tuple[list[int], list[list[int]]]:
    """``divide_regions`` on plain Python rows, replacing divided regions' entries in place.

    ``boxes_px`` are [x, y, w, h] lists, ``rows`` the ``RegionGeometry.rows``
    feature rows (None: no ground point). Returns (indices of the divided
    regions, the spot boxes cut off). The detector's per-frame entry point:
    a frame's few regions cost no array round trip. Regions farther than ``beyond_m`` are
    not tried: the detector passes its range for a camera without lens distortion, where the
    object part (inside the region's box: its bottom row at or above the region's) is at least
    as far away, so it would be dropped as beyond range all the same. ``lit``: whether a spot
    part is a light spot, given the object's and the spot's frame boxes; a division whose spot is not stands not (None: every
    division stands, as the paper's).
    """
    divided: list[int] = []
    spots: list[list[int]] = []
    for i, (box, area, row) in enumerate(zip(boxes_px, areas_px, rows, strict=True)):
        x, y, w, h = box
        # histograms of a region under min_height_px rows cannot resolve an object above a spot
        if row is None or h < params.min_height_px or row[3] > beyond_m:
            continue
        extent = area / max(w * h, 1)
        # NaN areas compare False
        if not (extent < params.max_extent or row[2] > params.max_area_m2):
            continue
        roi = np.zeros((h, w), np.uint8)
        cv2.drawContours(roi, contours, i, 1, thickness=cv2.FILLED, offset=(-x, -y))
        accepted = None
        for splitter, flat_field, upright_field in SPLITTERS:
            parts = splitter(roi, params)
            min_upright = None if upright_field is None else getattr(params, upright_field)
            accepted = _accept(
                geometry, parts, x, y, extent, row, getattr(params, flat_field), min_upright
            )
            if accepted is not None:
                break
        if accepted is None or (lit is not None and not lit(accepted[0][0], accepted[1])):
            continue
        body, spot, body_row = accepted
        boxes_px[i], areas_px[i], rows[i] = body[0], body[1], body_row
        divided.append(i)
        spots.append(spot)
    return divided, spots


def divide_regions(
    camera: CameraModel,
    contours: list[np.ndarray],
    boxes_px: np.ndarray,
    areas_px: np.ndarray,
    features: np.ndarray,
    valid: np.ndarray,
    params: DivisionParams = _DEFAULT_PARAMS,
    lit: Callable[[list[int], list[int]], bool] | None = None,
) -> Division:
    """Divide candidate regions into object + light spot; features recomputed for the objects.

    Inputs are aligned per region: OpenCV contours (frame coordinates), boxes
    (x, y, w, h), contour areas, and ``region_features`` rows and validity.
    Regions that are not divided pass through unchanged; ``lit`` as in ``divide_rows``.
    """
    boxes = np.asarray(boxes_px, np.int32).reshape(-1, 4)
    areas = np.asarray(areas_px, np.float64).reshape(-1)
    feats = np.asarray(features, np.float64).reshape(-1, features.shape[-1])
    valid = np.asarray(valid, bool).reshape(-1)
    box_rows, area_rows = boxes.tolist(), areas.tolist()
    rows = [row if ok else None for row, ok in zip(feats.tolist(), valid.tolist(), strict=True)]
    divided, spots = divide_rows(
        RegionGeometry(camera), contours, box_rows, area_rows, rows, params, lit=lit
    )
    out_boxes, out_areas, out_feats = boxes.copy(), areas.copy(), feats.copy()
    for i in divided:
        out_boxes[i], out_areas[i], out_feats[i] = box_rows[i], area_rows[i], rows[i]
    flags = np.zeros(len(boxes), bool)
    flags[divided] = True
    return Division(
        boxes_px=out_boxes,
        areas_px=out_areas,
        features=out_feats,
        valid=valid,
        divided=flags,
        spot_boxes_px=np.array(spots, np.int32).reshape(-1, 4),
    )
