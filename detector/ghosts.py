"""Steep cameras: a region where nothing changed since the last frame is no moving object.

Background subtraction (MOG2) marks what differs from its model of the background. When an
object that was part of that model leaves (a car parked in the first frame, which the model
learns as background, then drives off; a car that stood a few seconds), the ground it uncovers
differs from the model and is foreground (a "ghost") for seconds, until the model relearns it.
A ghost does not move: its pixels are the still ground, the same from frame to frame, while a
moving body changes the pixels along its outline every frame (the classic test: Cucchiara et
al., "Detecting moving objects, ghosts and shadows in video streams", 2003). On the car-park
development clip (camera looking 50 degrees down; frames 5-47, 290-390) the ghosts' foreground
pixels changed by more than ``CHANGE_DN`` between frames in 0-2.3 % of them, the pieces of the
moving cars and the walker in 7-98 % (but a piece on a car's windscreen that stood still in the
image while the car moved under it: 0.4 %); a region under ``MAX_STILL_SHARE`` is still.

A still region is kept and classified as any region (the paper's per-frame output is unchanged)
but follows no track (``detector.tracks.tracker``): a ghost neither starts a track nor
continues or joins a moving object's, so it can be no target. Gated to cameras looking steeply
down (``detector.tracks.footprint.is_steep``), where the development footage shows ghosts
splitting and taking over cars' tracks; the lamps' cameras and the paper's are unchanged (a
walker who stands still under a lamp keeps his track through the tracker's still hold).

Conventions: frames are uint8 grayscale of the camera's size; boxes OpenCV ``(x, y, w, h)``
pixels of that frame; the mask is the segmenter's final foreground mask of the frame (nonzero
is foreground); a pixel "changed" when its gray level differs from the last frame's by more
than ``CHANGE_DN`` (digital numbers, 0-255). A frame identical to the one before (a video's
repeated frame) is no new frame: the comparison stays with the last frame that differed.
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
