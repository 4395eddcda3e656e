"""CLAHE of a crop equal, bit for bit, to OpenCV's CLAHE of the whole frame (compiled, numba).

``CropCLAHE`` builds the tables of the tiles the crop needs and interpolates with the full
frame's weights; it checks itself against ``cv2.CLAHE.apply`` on probe frames when built and
falls back to OpenCV on the whole frame if any value differs.

Design: docs/design/region-of-interest.md (Equalisation)
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from numba import njit

_BINS = 256
# histograms per tile counted interleaved (``_tile_luts``, whose loop is written out for four)
_HISTOGRAM_COPIES = 4


@njit(cache=True, nogil=True)
def _tile_luts(
    src, tile_h, tile_w, tile_rows, tile_cols, clip_limit, lut_scale, pairs
):  # pragma: no cover - compiled
    """The look-up table of every tile in ``tile_rows`` x ``tile_cols`` (ranges of tile indices)
    of the uint8 frame ``src``, as OpenCV builds it, written as pairs: ``pairs[ty, k, v]`` holds
    the values for v of the tiles left and right of the k-th boundary (tiles k - 1 and k, clamped
    to the grid), the two tables a pixel between them interpolates, side by side in memory."""
    tiles_x = pairs.shape[1] - 1
    hist = np.empty(_BINS, np.int32)
    lut = np.empty(_BINS, np.float32)
    # _HISTOGRAM_COPIES histograms, pixel x counted in copy x % _HISTOGRAM_COPIES, then summed:
    # with one histogram, neighbouring pixels of one value (most of a dark frame) each wait for
    # the previous increment's store before loading the count again
    counts = np.empty((_HISTOGRAM_COPIES, _BINS), np.int32)
    whole_px = tile_w - tile_w % _HISTOGRAM_COPIES  # of a tile row, counted four at a time
    for ty in range(tile_rows[0], tile_rows[1]):
        for tx in range(tile_cols[0], tile_cols[1]):
            counts[:] = 0
            x0 = tx * tile_w
            for y in range(ty * tile_h, (ty + 1) * tile_h):
                row = src[y, x0 : x0 + tile_w]
                for x in range(0, whole_px, _HISTOGRAM_COPIES):
                    counts[0, row[x]] += 1
                    counts[1, row[x + 1]] += 1
                    counts[2, row[x + 2]] += 1
                    counts[3, row[x + 3]] += 1
                for x in range(whole_px, tile_w):
                    counts[0, row[x]] += 1
            for i in range(_BINS):
                hist[i] = counts[0, i] + counts[1, i] + counts[2, i] + counts[3, i]
            clipped = 0
            for i in range(_BINS):
                if hist[i] > clip_limit:
                    clipped += hist[i] - clip_limit
                    hist[i] = clip_limit
            batch = clipped // _BINS
            residual = clipped - batch * _BINS
            for i in range(_BINS):
                hist[i] += batch
            if residual != 0:
                step = max(_BINS // residual, 1)
                i = 0
                while i < _BINS and residual > 0:
                    hist[i] += 1
                    i += step
                    residual -= 1
            total = 0
            for i in range(_BINS):
                total += hist[i]
                # saturate_cast<uchar>(float): round half to even, then clamp (never needed here)
                lut[i] = min(
                    max(np.rint(np.float32(total) * lut_scale), np.float32(0.0)), np.float32(255.0)
                )
            pairs[ty, tx, :, 1] = lut
            pairs[ty, tx + 1, :, 0] = lut
            if tx == 0:
                pairs[ty, 0, :, 0] = lut
            if tx == tiles_x - 1:
                pairs[ty, tiles_x, :, 1] = lut


@njit(cache=True, nogil=True)
def _column_weights(cols, tile_w, offset, xa, xa1):  # pragma: no cover - compiled
    """Per column of the half-open range ``cols``: where the pair of tables it interpolates
    between starts in a tile row of the pairs, flattened (the tile boundary it lies after
    x 2 x 256), and OpenCV's float32 weights of the right and the left table."""
    one, half = np.float32(1.0), np.float32(0.5)
    inv_tw = one / np.float32(tile_w)
    for k in range(cols[1] - cols[0]):
        txf = np.float32(cols[0] + k) * inv_tw - half
        tx1 = int(math.floor(txf))
        xa[k] = txf - np.float32(tx1)
        xa1[k] = one - xa[k]
        offset[k] = (tx1 + 1) * 2 * _BINS


@njit(cache=True, nogil=True)
def _interpolate(src, pairs, rows, cols, tile_h, columns, dst):  # pragma: no cover - compiled
    """``dst[y - rows[0], x - cols[0]]`` for the frame's pixels ``rows`` x ``cols`` (ranges):
    OpenCV's float32 interpolation between the tables ``pairs`` (``_tile_luts``); ``columns``:
    ``_column_weights``' (offset, xa, xa1)."""
    offset, xa, xa1 = columns
    tiles_y = pairs.shape[0]
    # each tile row's pairs as one flat array, read at unsigned indices: a signed index costs a
    # test for negative (wrap-around) indices on every read
    flat_pairs = pairs.reshape((tiles_y, -1))
    two = np.uint64(2)
    # scalars, not array reads: the writes to dst could alias them, which keeps them in the loop
    row0, row1, col0, col1 = rows[0], rows[1], cols[0], cols[1]
    one, half = np.float32(1.0), np.float32(0.5)
    inv_th = one / np.float32(tile_h)
    for y in range(row0, row1):
        tyf = np.float32(y) * inv_th - half
        ty1 = int(math.floor(tyf))
        ya = tyf - np.float32(ty1)
        ya1 = one - ya
        upper = flat_pairs[max(ty1, 0)]
        lower = flat_pairs[min(ty1 + 1, tiles_y - 1)]
        src_row = src[y, col0:col1]
        dst_row = dst[y - row0]
        for k in range(col1 - col0):
            left = offset[k] + two * src_row[k]
            right = left + np.uint64(1)
            res = (upper[left] * xa1[k] + upper[right] * xa[k]) * ya1 + (
                lower[left] * xa1[k] + lower[right] * xa[k]
            ) * ya
            # a convex combination of 0..255 values: within 0..255 after rounding
            dst_row[k] = np.uint8(np.int32(np.rint(res)))


@njit(cache=True, nogil=True)
def _equalise(
    src, ranges, clip_limit, lut_scale, tile_h, tile_w, pairs, columns, dst
):  # pragma: no cover - compiled
    """``_tile_luts`` then ``_interpolate``, in one call from Python (each call from Python
    costs microseconds of argument checks); ``ranges``: (tile rows, tile cols, rows, cols)."""
    _tile_luts(src, tile_h, tile_w, ranges[0], ranges[1], clip_limit, lut_scale, pairs)
    _interpolate(src, pairs, ranges[2], ranges[3], tile_h, columns, dst)


def tiles_for(start_px: int, end_px: int, tile_px: int, n_tiles: int) -> tuple[int, int]:
    """Half-open range of the tiles whose tables OpenCV interpolates between for pixels
    ``start_px .. end_px - 1``: pixel p lies between tiles floor(p / tile - 0.5) and the next
    (clamped to the grid)."""
    first = max(0, math.floor(start_px / tile_px - 0.5))
    last = min(n_tiles - 1, math.floor((end_px - 1) / tile_px - 0.5) + 1)
    return first, last + 1


class CropCLAHE:
    """``cv2.createCLAHE(clip_limit, (tiles, tiles)).apply(frame)[rows, cols]`` computed on the
    crop only; ``apply(frame)`` writes it into ``self.out`` (a buffer reused across frames,
    (rows, cols) of the crop) and returns it.

    ``rows``/``cols``: half-open pixel ranges of a ``frame_height_px`` x ``frame_width_px``
    frame. ``exact`` says whether the compiled path is used (it matched OpenCV on the probe
    frames); otherwise OpenCV equalises the whole frame and the crop is copied out of it.
    """

    def __init__(
        self,
        clip_limit: float,
        tiles: int,
        frame_shape_px: tuple[int, int],
        rows: tuple[int, int],
        cols: tuple[int, int],
    ) -> None:
        h, w = frame_shape_px
        self._rows = np.array(rows, np.int64)
        self._cols = np.array(cols, np.int64)
        self._slices = (slice(*rows), slice(*cols))
        self._opencv = cv2.createCLAHE(clipLimit=clip_limit, tileGridSize=(tiles, tiles))
        self.out = np.empty((rows[1] - rows[0], cols[1] - cols[0]), np.uint8)
        self.exact = h % tiles == 0 and w % tiles == 0
        if not self.exact:
            return
        self._tile_h, self._tile_w = h // tiles, w // tiles
        tile_px = self._tile_h * self._tile_w
        # OpenCV: int(clipLimit * tileSizeTotal / histSize) in double, at least 1; scale in float32
        self._clip = max(int(clip_limit * tile_px / _BINS), 1)
        self._scale = np.float32(_BINS - 1) / np.float32(tile_px)
        self._tile_rows = np.array(tiles_for(*rows, self._tile_h, tiles), np.int64)
        self._tile_cols = np.array(tiles_for(*cols, self._tile_w, tiles), np.int64)
        # tables of tiles outside the ranges stay 0 and are never read
        self._pairs = np.zeros((tiles, tiles + 1, _BINS, 2), np.float32)
        n_cols = cols[1] - cols[0]
        self._columns = (
            np.empty(n_cols, np.uint64),
            np.empty(n_cols, np.float32),
            np.empty(n_cols, np.float32),
        )
        _column_weights(self._cols, self._tile_w, *self._columns)
        self._ranges = np.stack([self._tile_rows, self._tile_cols, self._rows, self._cols])
        self.exact = self._matches_opencv(h, w)

    @property
    def histogram_share(self) -> float:
        """Fraction of the frame's pixels whose histograms are taken (1 on the OpenCV path)."""
        if not self.exact:
            return 1.0
        tiles = self._pairs.shape[0]
        return float(np.diff(self._tile_rows)[0] * np.diff(self._tile_cols)[0]) / tiles**2

    def apply(self, gray: np.ndarray) -> np.ndarray:
        """Equalise the crop of one uint8 frame of this object's frame shape into ``self.out``."""
        if not self.exact:
            np.copyto(self.out, self._opencv.apply(gray)[self._slices])
            return self.out
        _equalise(
            gray, self._ranges, self._clip, self._scale, self._tile_h, self._tile_w, self._pairs,
            self._columns, self.out,
        )  # fmt: skip
        return self.out

    def _matches_opencv(self, h: int, w: int) -> bool:
        """Whether the compiled path gives OpenCV's values on probe frames: a noisy ramp (tables
        clipped), flat noise (most counts in a few bins: large residuals) and uniform noise."""
        rng = np.random.default_rng(0)
        ramp = np.linspace(10.0, 120.0, h)[:, None] + rng.normal(0.0, 9.0, (h, w))
        probes = (
            np.clip(ramp, 0, 255).astype(np.uint8),
            np.clip(rng.normal(40.0, 2.0, (h, w)), 0, 255).astype(np.uint8),
            rng.integers(0, 256, (h, w), dtype=np.uint8),
        )
        self.exact = True
        for frame in probes:
            if not np.array_equal(self.apply(frame), self._opencv.apply(frame)[self._slices]):
                return False
        return True
