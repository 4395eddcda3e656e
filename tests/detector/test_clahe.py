"""The crop's CLAHE (detector.clahe) against OpenCV's CLAHE of the whole frame: equal bit for bit."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from detector.clahe import CropCLAHE, tiles_for

SIZES_PX = [(240, 424), (240, 320), (360, 480), (480, 640), (64, 96)]


def frames(shape_px: tuple[int, int], rng: np.random.Generator) -> list[np.ndarray]:
    """Uniform noise (no clipping), a dark noisy ramp (tables clipped), a flat dark frame with
    a bright disc (most counts in a few bins: large residuals), a constant frame (everything
    clipped), and a saturated one."""
    h, w = shape_px
    ramp = np.linspace(15.0, 95.0, h)[:, None] + rng.normal(0.0, 6.0, (h, w))
    disc = np.clip(rng.normal(40.0, 2.5, (h, w)), 0, 255).astype(np.uint8)
    cv2.circle(disc, (w // 3, h // 2), h // 5, 210, -1)
    return [
        rng.integers(0, 256, (h, w), dtype=np.uint8),
        np.clip(ramp, 0, 255).astype(np.uint8),
        disc,
        np.full((h, w), 37, np.uint8),
        np.clip(rng.normal(250.0, 8.0, (h, w)), 0, 255).astype(np.uint8),
    ]


@pytest.mark.parametrize("shape_px", SIZES_PX)
@pytest.mark.parametrize("clip_limit", [3.0, 1.0, 40.0])
def test_crop_equals_opencv_on_the_whole_frame(shape_px, clip_limit):
    h, w = shape_px
    rng = np.random.default_rng(h + w)
    opencv = cv2.createCLAHE(clipLimit=clip_limit, tileGridSize=(8, 8))
    crops = [((0, h), (0, w)), ((h // 3, h), (0, w)), ((7, h - 5), (11, w - 3)), ((h - 1, h), (w // 2, w))]
    crops += [((int(a), h), (0, w)) for a in rng.integers(0, h, 4)]
    for rows, cols in crops:
        mine = CropCLAHE(clip_limit, 8, shape_px, rows, cols)
        assert mine.exact
        for frame in frames(shape_px, rng):
            want = opencv.apply(frame)[rows[0] : rows[1], cols[0] : cols[1]]
            np.testing.assert_array_equal(mine.apply(frame), want, err_msg=f"{rows} {cols}")


def test_only_the_tiles_the_crop_needs_are_read():
    # the suburban lamp camera's crop: rows 78-239 of 240 need tile rows 2-7 (30 px tiles)
    assert tiles_for(78, 240, 30, 8) == (2, 8)
    assert tiles_for(74, 240, 30, 8) == (1, 8) and tiles_for(75, 240, 30, 8) == (2, 8) and tiles_for(0, 240, 30, 8) == (0, 8)
    mine = CropCLAHE(3.0, 8, (240, 424), (78, 240), (0, 424))
    assert mine.histogram_share == 0.75
    frame = np.random.default_rng(1).integers(0, 256, (240, 424), dtype=np.uint8)
    want = mine.apply(frame).copy()
    frame[:60] = 0  # tiles 0 and 1 are never read
    np.testing.assert_array_equal(mine.apply(frame), want)


def test_frames_opencv_pads_are_equalised_by_opencv():
    mine = CropCLAHE(3.0, 8, (100, 130), (40, 100), (0, 130))
    assert not mine.exact and mine.histogram_share == 1.0
    frame = np.random.default_rng(2).integers(0, 256, (100, 130), dtype=np.uint8)
    want = cv2.createCLAHE(3.0, (8, 8)).apply(frame)[40:]
    np.testing.assert_array_equal(mine.apply(frame), want)
