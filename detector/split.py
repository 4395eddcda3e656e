"""The pixel half of region division (``detector.divide``): where in a region's mask the
object ends and its light spot begins, read from the mask's histograms; and the thresholds
of the whole division (``DivisionParams``).

Column heights separate the body from side pixels, row widths place the body's foot row, and
``split_at_widening`` reads a compact blob on a wider flat part from the row widths alone. All
in the region's own bounding box, pixels.

Design: docs/design/modules.md (Region division)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from detector.classes import TABLE1

# Table 1: the largest silhouette of any target class is a vehicle seen from
# the side, 4.6 m long x 2 m high; a region estimated larger is more than one thing.
LARGEST_CLASS_AREA_M2 = max(
    max(size.width_m[1], size.length_m[1]) * size.height_m[1] for size in TABLE1.values()
)


@dataclass(frozen=True)
class DivisionParams:
    """Thresholds of the division; fractions are of pixel counts unless named ``_m``.

    ``max_extent``: regions with extent (contour area / box area) below it are candidates.
    ``max_area_m2``: regions with estimated contour area above it are candidates.
    ``tall_fraction``: body columns are at least this fraction of the tallest column.
    ``max_side_height_fraction``: a spot is at most this fraction of the body's height (px).
    ``max_spot_aspect``: a spot part's box height / width (px) is at most this (it is flat).
    ``min_side_fraction``: the side pixels hold at least this fraction of the region's pixels.
    ``max_spot_height_to_width``: the spot's estimated height / width (m) is at most this.
    ``wide_row_factor``: a row is part of a spot in front when it is this much wider than the body.
    ``spot_row_fraction``: spot rows have side pixels at least this fraction of the widest side row.
    ``min_height_px``: shorter regions are not analysed (too few rows for the histograms).
    ``widen_start``: in ``split_at_widening``, a row this much wider than every row above starts the spot.
    ``widen_ratio``: ... and the spot's rows are at least this many times the blob's widest row.
    ``min_top_rows``: ... the blob has at least this many rows (its roof rows widen fast too).
    ``min_object_extent``: ... the blob fills at least this fraction of its box (it is compact).
    ``max_beam_height_to_width``: ... the spot's estimated height / width (m) is at most this
    (a beam reaching from the object's base to near the camera is long on the ground, and
    read as upright at its near end it comes out taller than a spot beside a walker).
    ``min_beam_object_height_to_width``: ... the blob's estimated height / width (m) is at least
    this; it replaces "more upright than the whole", which a beam reaching near the camera
    (estimated tall) defeats. A head-on car is ~0.8, a side-view car's cabin ~0.25.
    """

    max_extent: float = 0.6
    max_area_m2: float = LARGEST_CLASS_AREA_M2
    tall_fraction: float = 0.5
    max_side_height_fraction: float = 0.45
    max_spot_aspect: float = 0.7
    min_side_fraction: float = 0.1
    max_spot_height_to_width: float = 0.6
    wide_row_factor: float = 1.5
    spot_row_fraction: float = 0.25
    min_height_px: int = 16
    widen_start: float = 1.25
    widen_ratio: float = 2.0
    min_top_rows: int = 4
    min_object_extent: float = 0.5
    max_beam_height_to_width: float = 1.0
    min_beam_object_height_to_width: float = 0.4

    def __post_init__(self) -> None:
        for name in (
            "max_extent",
            "tall_fraction",
            "max_side_height_fraction",
            "min_side_fraction",
            "spot_row_fraction",
            "min_object_extent",
        ):
            value = getattr(self, name)
            if not 0.0 < value <= 1.0:
                raise ValueError(f"DivisionParams.{name} must be in (0, 1], got {value!r}")
        for name in (
            "max_area_m2",
            "max_spot_aspect",
            "max_spot_height_to_width",
            "max_beam_height_to_width",
            "min_beam_object_height_to_width",
        ):
            value = getattr(self, name)
            if not value > 0.0:
                raise ValueError(f"DivisionParams.{name} must be > 0, got {value!r}")
        if not (isinstance(self.min_height_px, int) and self.min_height_px >= 6):
            raise ValueError(
                f"DivisionParams.min_height_px must be an integer >= 6, got {self.min_height_px!r}"
            )
        if not (isinstance(self.min_top_rows, int) and self.min_top_rows >= 2):
            raise ValueError(
                f"DivisionParams.min_top_rows must be an integer >= 2, got {self.min_top_rows!r}"
            )
        for name in ("widen_start", "widen_ratio"):
            value = getattr(self, name)
            if not value > 1.0:
                raise ValueError(f"DivisionParams.{name} must be > 1, got {value!r}")
        if not self.wide_row_factor > 1.0:
            raise ValueError(
                f"DivisionParams.wide_row_factor must be > 1, got {self.wide_row_factor!r}"
            )


def _count(occ: np.ndarray, axis: int) -> list[int]:
    """Set pixels per column (axis 0) or row (axis 1) of a boolean mask, as a list."""
    # add.reduce in int32: half the cost of count_nonzero's axis path on these small masks
    return np.add.reduce(occ, axis=axis, dtype=np.int32).tolist()


def split_object_and_spot(
    roi: np.ndarray, params: DivisionParams = DivisionParams()
) -> tuple[np.ndarray, np.ndarray] | None:
    """Split one region's filled mask ``roi`` (h, w) into (object, spot) boolean masks, or None.

    Pixel-only test (histograms); the metric criteria are applied by ``divide_regions``.
    """
    occ = roi if roi.dtype == bool else roi > 0
    h, w = occ.shape
    if h < 6 or w < 6:
        return None
    # most candidates fail one of the first two tests: plain Python on the histograms up to there
    col_h = _count(occ, axis=0)
    tallest = max(col_h)
    if tallest == 0:
        return None
    tall = [j for j, n in enumerate(col_h) if n >= params.tall_fraction * tallest]
    c0, c1 = tall[0], tall[-1]
    n_side = sum(col_h[:c0]) + sum(col_h[c1 + 1 :])
    if n_side < params.min_side_fraction * sum(col_h):
        return None

    tall_w = _count(occ[:, c0 : c1 + 1], axis=1)
    body_rows = [r for r, n in enumerate(tall_w) if n]
    b_top, b_bottom = body_rows[0], body_rows[-1]
    # slivers of the body's own outline (a shoulder, a sleeve) fall outside the
    # tall columns too; the spot's rows are those where the side part is wide
    left_w = _count(occ[:, :c0], axis=1)
    right_w = _count(occ[:, c1 + 1 :], axis=1)
    side_w = [left + right for left, right in zip(left_w, right_w, strict=True)]
    widest = max(side_w)
    side_rows = [r for r, n in enumerate(side_w) if n >= params.spot_row_fraction * widest]
    s_top, s_bottom = side_rows[0], side_rows[-1]
    side_h = s_bottom - s_top + 1
    if side_h > params.max_side_height_fraction * (b_bottom - b_top + 1):
        return None
    side = occ.copy()
    side[:, c0 : c1 + 1] = False

    band_end = s_bottom + 1
    if s_bottom < b_bottom - max(2, side_h // 4):
        # spot behind the object (farther away, so higher in the image): the feet are the
        # bottom; a spot far enough behind to reach the upper body would hardly join it
        if s_bottom < (b_top + b_bottom) / 2:
            return None
        foot = b_bottom
    elif min(max(left_w), max(right_w)) >= params.spot_row_fraction * widest:
        # spot in front of the object: the body ends at the last narrow row above the spot
        band_end = h
        row_w = np.count_nonzero(occ[b_top : s_top + 1], axis=1)
        body_w = float(np.median(row_w[:-1])) if len(row_w) > 1 else float(c1 - c0 + 1)
        narrow = np.flatnonzero(row_w <= params.wide_row_factor * body_w)
        foot = b_top + int(narrow[-1]) if len(narrow) else s_top - 1
    else:
        # spot beside the object, about as far away: feet at the spot's widest row
        band_end = h
        rows = side_w[s_top : s_bottom + 1]
        foot = s_top + rows.index(max(rows))
    if foot <= b_top + 2:
        return None

    # the spot: side pixels in its rows, and whatever lies under the feet;
    # everything else, slivers of the outline included, is the object
    spot = np.zeros_like(occ)
    spot[s_top:band_end] = side[s_top:band_end]
    spot[foot + 1 :, c0 : c1 + 1] = occ[foot + 1 :, c0 : c1 + 1]
    body = occ & ~spot
    spot_rows = np.flatnonzero(spot.any(axis=1))
    spot_cols = np.flatnonzero(spot.any(axis=0))
    if len(spot_rows) == 0:
        return None
    spot_aspect = (spot_rows[-1] - spot_rows[0] + 1) / (spot_cols[-1] - spot_cols[0] + 1)
    if spot_aspect > params.max_spot_aspect:
        return None
    return body, spot


def split_at_widening(
    roi: np.ndarray, params: DivisionParams = DivisionParams()
) -> tuple[np.ndarray, np.ndarray] | None:
    """Split a compact blob from the much wider flat part it stands on: (object, spot) masks, or None.

    ``roi`` is one region's filled mask (h, w), row 0 at the top. Pixel-only
    test on the row widths (the horizontal histogram); the metric criteria are
    applied by ``divide_rows``.
    """
    occ = roi if roi.dtype == bool else roi > 0
    h, w = occ.shape
    start = params.min_top_rows
    if h < 2 * start or w < 6:
        return None
    row_w = _count(occ, axis=1)
    widest_above = max(row_w[:start])
    cut = None
    # the beam fans out over some rows: look ahead for the rows to reach widen_ratio times the
    # blob, then cut at the first row clearly wider than the blob
    for r in range(start, h - start):
        if max(row_w[r : r + max(3, r // 2)]) >= params.widen_ratio * widest_above:
            cut = next(
                (c for c in range(r, h) if row_w[c] > params.widen_start * widest_above), None
            )
            break
        widest_above = max(widest_above, row_w[r])
    if cut is None:
        return None
    # a spot in front fans out from the blob's base to many times its width, and its rows
    # stay wider than the blob; an arm or a bag at mid height has the narrow body below again
    below = sorted(row_w[cut:])
    if (
        below[-1] < params.widen_ratio * widest_above
        or below[len(below) // 2] < params.widen_start * widest_above
    ):
        return None
    top = row_w[:cut]
    peak = top.index(widest_above)
    neck_w = min(top[peak:])
    # the last of equally narrow rows: the blob's base is just above the spot
    neck = cut - 1 - top[::-1].index(neck_w)
    if neck + 1 < start:
        return None
    body = occ.copy()
    body[neck + 1 :] = False
    cols = np.flatnonzero(np.add.reduce(body[: neck + 1], axis=0, dtype=np.int32))
    if len(cols) == 0:
        return None
    if sum(top[: neck + 1]) < params.min_object_extent * (neck + 1) * (cols[-1] - cols[0] + 1):
        return None
    return body, occ & ~body
