"""Steep cameras: a region where nothing changed since the last frame is no moving object.

A region whose share of changed foreground pixels is under ``MAX_STILL_SHARE`` is still (a
"ghost" of background uncovered by an object leaving); it is classified but follows no track.
Only for cameras looking steeply down (``detector.tracks.footprint.is_steep``).

Conventions: frames are uint8 grayscale of the camera's size; boxes OpenCV ``(x, y, w, h)``
pixels of that frame; the mask is the segmenter's final foreground mask of the frame (nonzero
is foreground); a pixel "changed" when its gray level differs from the last frame's by more
than ``CHANGE_DN`` (digital numbers, 0-255). A frame identical to the one before (a video's
repeated frame) is no new frame: the comparison stays with the last frame that differed.

Design: docs/design/modules.md (Ghosts)
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np

#: A pixel changed between frames when it differs by more than this, gray levels: far above the
#: frame-to-frame noise of still ground (on the development clip at the detector's 424 px: 0.4
#: levels standard deviation, 99.9 % of pixels within 3) and under the contrast a body's outline
#: has with what it moves over
CHANGE_DN = 12
#: A region whose foreground pixels changed in under this share is still (module docstring)
MAX_STILL_SHARE = 0.05


class StillRegions:
    """Which of a frame's regions did not change since the last frame (module docstring)."""

    def __init__(self, change_dn: int = CHANGE_DN, max_still_share: float = MAX_STILL_SHARE) -> None:
        if not 0 <= change_dn < 255:
            raise ValueError(f"StillRegions change_dn: must be in [0, 255), got {change_dn!r}")
        if not 0.0 < max_still_share <= 1.0:
            raise ValueError(f"StillRegions max_still_share: must be in (0, 1], got {max_still_share!r}")
        self.change_dn, self.max_still_share = change_dn, max_still_share
        self._current: np.ndarray | None = None
        self._previous: np.ndarray | None = None

    def reset(self) -> None:
        """Forget the frames seen (the next frame has nothing to compare with)."""
        self._current = self._previous = None

    def next_frame(self, gray: np.ndarray) -> None:
        """Take this frame (call once per frame, before ``flags``)."""
        if self._current is not None and not cv2.hasNonZero(cv2.absdiff(gray, self._current)):
            return  # a repeated frame: compare with the last frame that differed
        self._previous, self._current = self._current, gray.copy()

    def flags(self, mask: np.ndarray, boxes_px: Sequence[Sequence[int]]) -> list[bool]:
        """Per box, whether the foreground pixels of ``mask`` inside it are still (all False for
        the first frame)."""
        if self._previous is None or not boxes_px:
            return [False] * len(boxes_px)
        out = []
        for x, y, w, h in boxes_px:
            fg = mask[y: y + h, x: x + w] > 0
            n = int(np.count_nonzero(fg))
            if n == 0:
                out.append(False)
                continue
            diff = cv2.absdiff(self._current[y: y + h, x: x + w], self._previous[y: y + h, x: x + w])
            changed = int(np.count_nonzero((diff > self.change_dn) & fg))
            out.append(changed < self.max_still_share * n)
        return out
