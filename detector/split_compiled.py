"""``detector.split``'s two pixel tests compiled (numba), for the detector's frames.

Why: a candidate region's histograms cost about fifty numpy and list calls in
``split_object_and_spot`` (tens of microseconds per candidate, more after MOG2 has walked the
caches); compiled, one call. Each function here is its ``detector.split`` namesake step for
step, on integer pixel counts and the same float64 comparisons, and returns the same masks
(``tests/detector/test_split_compiled.py`` compares them on many masks). ``detector.split``
keeps the readable reference and the thresholds (``DivisionParams``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from detector.split import DivisionParams

__all__ = ["load", "split_at_widening", "split_object_and_spot"]

# frozen, so one shared default instance is safe
_DEFAULT_PARAMS = DivisionParams()


@njit(cache=True, nogil=True)
def _row_and_column_counts(mask):  # pragma: no cover - compiled
    """Set pixels per row and per column of a boolean mask (int64 each)."""
    h, w = mask.shape
    rows = np.zeros(h, np.int64)
    cols = np.zeros(w, np.int64)
    for r in range(h):
        for c in range(w):
            if mask[r, c]:
                rows[r] += 1
                cols[c] += 1
    return rows, cols


@njit(cache=True, nogil=True)
def _first_and_last_at_least(values, threshold):  # pragma: no cover - compiled
    """The first and last index whose value is at least ``threshold`` (-1, -1: none)."""
    first, last = -1, -1
    for i in range(len(values)):
        if values[i] >= threshold:
            if first < 0:
                first = i
            last = i
    return first, last


@njit(cache=True, nogil=True)
def _spot_split(occ, tall_fraction, min_side_fraction, spot_row_fraction, max_side_height_fraction,
                wide_row_factor, max_spot_aspect):  # fmt: skip  # pragma: no cover - compiled
    """(split?, object, spot) of a filled uint8 mask (nonzero: set), as ``detector.split``'s
    ``split_object_and_spot``."""
    h, w = occ.shape
    none = np.zeros((0, 0), np.bool_)
    if h < 6 or w < 6:
        return False, none, none
    mask = occ != 0
    _, col_h = _row_and_column_counts(mask)
    tallest = col_h.max()
    if tallest == 0:
        return False, none, none
    c0, c1 = _first_and_last_at_least(col_h, tall_fraction * tallest)
    n_side = col_h[:c0].sum() + col_h[c1 + 1 :].sum()
    if n_side < min_side_fraction * col_h.sum():
        return False, none, none
    tall_w = np.zeros(h, np.int64)
    left_w = np.zeros(h, np.int64)
    right_w = np.zeros(h, np.int64)
    for r in range(h):
        for c in range(w):
            if mask[r, c]:
                if c < c0:
                    left_w[r] += 1
                elif c > c1:
                    right_w[r] += 1
                else:
                    tall_w[r] += 1
    b_top, b_bottom = _first_and_last_at_least(tall_w, 1)
    side_w = left_w + right_w
    widest = side_w.max()
    s_top, s_bottom = _first_and_last_at_least(side_w, spot_row_fraction * widest)
    side_h = s_bottom - s_top + 1
    if side_h > max_side_height_fraction * (b_bottom - b_top + 1):
        return False, none, none
    band_end = s_bottom + 1
    if s_bottom < b_bottom - max(2, side_h // 4):
        if s_bottom < (b_top + b_bottom) / 2:
            return False, none, none
        foot = b_bottom
    elif min(left_w.max(), right_w.max()) >= spot_row_fraction * widest:
        band_end = h
        row_w = (tall_w + side_w)[b_top : s_top + 1]
        body_w = np.median(row_w[:-1]) if len(row_w) > 1 else float(c1 - c0 + 1)
        foot = s_top - 1
        for r in range(len(row_w)):
            if row_w[r] <= wide_row_factor * body_w:
                foot = b_top + r
    else:
        band_end = h
        foot = s_top
        for r in range(s_top, s_bottom + 1):
            if side_w[r] > side_w[foot]:  # the first of the widest
                foot = r
    if foot <= b_top + 2:
        return False, none, none
    spot = np.zeros((h, w), np.bool_)
    for r in range(s_top, band_end):
        for c in range(w):
            if c < c0 or c > c1:
                spot[r, c] = mask[r, c]
    for r in range(foot + 1, h):
        for c in range(c0, c1 + 1):
            spot[r, c] = mask[r, c]
    body = mask & ~spot
    r0, r1, k0, k1 = -1, -1, w, -1
    for r in range(h):
        for c in range(w):
            if spot[r, c]:
                if r0 < 0:
                    r0 = r
                r1 = r
                k0 = min(k0, c)
                k1 = max(k1, c)
    if r0 < 0:
        return False, none, none
    if (r1 - r0 + 1) / (k1 - k0 + 1) > max_spot_aspect:
        return False, none, none
    return True, body, spot


@njit(cache=True, nogil=True)
def _widening_split(occ, start, widen_ratio, widen_start,
                    min_object_extent):  # fmt: skip  # pragma: no cover - compiled
    """(split?, object, spot) of a filled uint8 mask (nonzero: set), as ``detector.split``'s
    ``split_at_widening``."""
    h, w = occ.shape
    none = np.zeros((0, 0), np.bool_)
    if h < 2 * start or w < 6:
        return False, none, none
    mask = occ != 0
    row_w, _ = _row_and_column_counts(mask)
    widest_above = row_w[:start].max()
    cut = -1
    found = False
    for r in range(start, h - start):
        if row_w[r : r + max(3, r // 2)].max() >= widen_ratio * widest_above:
            found = True
            for c in range(r, h):
                if row_w[c] > widen_start * widest_above:
                    cut = c
                    break
            break
        widest_above = max(widest_above, row_w[r])
    if not found or cut < 0:
        return False, none, none
    below = np.sort(row_w[cut:])
    if below[-1] < widen_ratio * widest_above or below[len(below) // 2] < widen_start * widest_above:
        return False, none, none
    peak = 0
    while row_w[peak] != widest_above:  # the first row as wide as the widest above the cut
        peak += 1
    neck_w = row_w[peak:cut].min()
    neck = cut - 1
    while row_w[neck] != neck_w:  # the last of equally narrow rows
        neck -= 1
    if neck + 1 < start:
        return False, none, none
    body = mask.copy()
    body[neck + 1 :] = False
    k0, k1 = w, -1
    for r in range(neck + 1):
        for c in range(w):
            if body[r, c]:
                k0 = min(k0, c)
                k1 = max(k1, c)
    if k1 < 0:
        return False, none, none
    if row_w[: neck + 1].sum() < min_object_extent * (neck + 1) * (k1 - k0 + 1):
        return False, none, none
    return True, body, mask & ~body


def split_object_and_spot(
    roi: np.ndarray, params: DivisionParams = _DEFAULT_PARAMS
) -> tuple[np.ndarray, np.ndarray] | None:
    """``detector.split.split_object_and_spot`` of a uint8 mask (nonzero: set), compiled."""
    ok, body, spot = _spot_split(
        roi, params.tall_fraction, params.min_side_fraction, params.spot_row_fraction,
        params.max_side_height_fraction, params.wide_row_factor, params.max_spot_aspect,
    )  # fmt: skip
    return (body, spot) if ok else None


def split_at_widening(
    roi: np.ndarray, params: DivisionParams = _DEFAULT_PARAMS
) -> tuple[np.ndarray, np.ndarray] | None:
    """``detector.split.split_at_widening`` of a uint8 mask (nonzero: set), compiled."""
    ok, body, spot = _widening_split(
        roi, params.min_top_rows, params.widen_ratio, params.widen_start, params.min_object_extent
    )
    return (body, spot) if ok else None


def load(params: DivisionParams = _DEFAULT_PARAMS) -> None:
    """Load (or compile) both tests for ``params``' argument types now: a detector calls this when
    built, so its first candidate region does not pay the tens of milliseconds of loading."""
    probe = np.ones((8, 8), np.uint8)
    split_object_and_spot(probe, params)
    split_at_widening(probe, params)
