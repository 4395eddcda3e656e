"""The last step of a frame: canvas radiance -> the camera's 8-bit frame, redoing only what moved.

Most of a street camera's view is still from one frame to the next: the
lit background changes only when a lamp changes level. So the frame of the
background alone (radiance -> DN -> lens remap, ``citysim.render.canvas``) is kept,
and a frame is that cached frame with the *boxes* that changed - where
agents, spots, glare, crowns or insects were drawn on the canvas - converted
and remapped again. Only the boxes are ever converted to DN and put back to
the background; when they cover much of the canvas, the lens remap is done
for the whole frame at once instead of box by box.

Light that is added on top of everything and does not move (the street
lamps' own glare) is kept as a separate radiance layer: it is part of the
cached frame and added again inside every redone box.

Conventions: canvas and frame pixels of ``citysim.render.canvas``; boxes are
(x0, y0, x1, y1) with exclusive ends; radiance in linear full-scale units.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import cv2
import numpy as np

from citysim.render import light
from citysim.render.canvas import Canvas
from citysim.render.kernels import merge_box_list

#: Redo the whole frame when the changed boxes cover more than this fraction of the canvas.
#: Boxes cost about what the whole frame costs per pixel plus a fixed ~10 OpenCV calls each,
#: but the whole frame also touches the unchanged pixels' memory, which in a simulation
#: (a detector between two frames) is cold.
WHOLE_FRAME_FRACTION = 0.8
#: Fixed cost of one box, in canvas pixels of work.
BOX_COST_PX = 2500


class FrameOutput:
    """One camera's canvas radiance buffer and its conversion to frames.

    ``work`` is the canvas the renderer draws a frame on. Between frames it
    holds the still view (``set_background``, ``still_changed``); ``finish``
    turns it into the frame and puts the still view back in the boxes that
    were drawn on.
    """

    def __init__(self, canvas: Canvas) -> None:
        self.canvas = canvas
        self.key: object = None
        h, w = canvas.shape
        self.work = np.zeros((h, w), np.float32)
        #: the still view's radiance (lit background, crowns at their current poses)
        self.still = np.zeros((h, w), np.float32)
        self._glare = np.zeros((h, w), np.float32)
        self._glare_boxes = np.zeros((0, 4), np.int64)
        self._dn = np.zeros((h, w), np.uint8)
        self._static_dn = self._dn
        self._static_frame = canvas.to_frame(self._dn)

    def set_background(
        self,
        key: object,
        background: np.ndarray,
        glare: np.ndarray,
        glare_boxes: np.ndarray,
        redraw: Callable[[np.ndarray], object] | None = None,
    ) -> None:
        """A new still view: ``background`` radiance (copied) and the lamps' ``glare`` radiance
        layer (zero outside ``glare_boxes`` (N, 4)); ``redraw(still)``, if given, draws on
        the copy first. ``key`` names the view."""
        self.key = key
        self.still = background.copy()
        if redraw is not None:
            redraw(self.still)
        np.copyto(self.work, self.still)
        self._glare = glare
        self._glare_boxes = np.asarray(glare_boxes, dtype=np.int64).reshape(-1, 4)
        still = cv2.add(self.still, glare) if len(self._glare_boxes) else self.still
        self._static_dn = light.radiance_to_dn(still)
        self._dn = self._static_dn.copy()
        self._static_frame = self.canvas.to_frame(self._static_dn).copy()

    def still_changed(self, boxes: Sequence[Sequence[int]]) -> None:
        """``still`` was drawn on inside canvas ``boxes``: bring the cached frame up to date."""
        if not len(boxes):
            return
        b = np.array(boxes, dtype=np.int64).reshape(-1, 4)
        glare = self._glare_touching(b)
        for (x0, y0, x1, y1), add_glare in zip(b.tolist(), glare, strict=True):
            view = self.still[y0:y1, x0:x1]
            if add_glare:
                view = cv2.add(view, self._glare[y0:y1, x0:x1])
            light.radiance_to_dn(view, out=self._static_dn[y0:y1, x0:x1])
            self.work[y0:y1, x0:x1] = self.still[y0:y1, x0:x1]
            self._dn[y0:y1, x0:x1] = self._static_dn[y0:y1, x0:x1]
        for box in self.canvas.frame_boxes(b).tolist():
            if box[2] > box[0] and box[3] > box[1]:
                self.canvas.remap_box(self._static_dn, box, self._static_frame)

    def finish(self, boxes: Sequence[Sequence[int]]) -> np.ndarray:
        """The frame (uint8, frame size, a fresh array) of ``work`` where everything drawn
        since the last call lies inside canvas ``boxes``. Puts the background back into
        ``work``."""
        canvas = self.canvas
        h, w = canvas.shape
        merged = merge_boxes(boxes)
        b = np.array(merged, dtype=np.int64).reshape(-1, 4)
        work, dn = self.work, self._dn
        for (x0, y0, x1, y1), glare in zip(merged, self._glare_touching(b), strict=True):
            view = work[y0:y1, x0:x1]
            if glare:  # added on the way out, not to work: boxes may overlap
                view = cv2.add(view, self._glare[y0:y1, x0:x1])
            light.radiance_to_dn(view, out=dn[y0:y1, x0:x1])
        area = int(((b[:, 2] - b[:, 0]) * (b[:, 3] - b[:, 1])).sum())
        if area + BOX_COST_PX * len(b) > WHOLE_FRAME_FRACTION * h * w:
            frame = canvas.to_frame(dn).copy() if canvas.remap_maps is None else canvas.to_frame(dn)
        else:
            frame = self._static_frame.copy()
            for box in canvas.frame_boxes(b).tolist():
                if box[2] > box[0] and box[3] > box[1]:
                    canvas.remap_box(dn, box, frame)
        background, still_dn = self.still, self._static_dn
        for x0, y0, x1, y1 in merged:
            work[y0:y1, x0:x1] = background[y0:y1, x0:x1]
            dn[y0:y1, x0:x1] = still_dn[y0:y1, x0:x1]
        return frame

    def _glare_touching(self, boxes: np.ndarray) -> list[bool]:
        """Per box, whether any of the still glare lies in it."""
        g = self._glare_boxes
        if not len(g):
            return [False] * len(boxes)
        hit = (
            (boxes[:, None, 0] < g[None, :, 2])
            & (g[None, :, 0] < boxes[:, None, 2])
            & (boxes[:, None, 1] < g[None, :, 3])
            & (g[None, :, 1] < boxes[:, None, 3])
        )
        return hit.any(axis=1).tolist()


def merge_boxes(boxes: Sequence[Sequence[int]]) -> list[tuple[int, int, int, int]]:
    """Boxes (x0, y0, x1, y1) joined where one box costs less than two: their joint box
    holds at most BOX_COST_PX more pixels than the two apart (``citysim.render.kernels.merge_box_list``).
    Empty boxes are dropped."""
    if not len(boxes):
        return []
    merged = merge_box_list(np.array(boxes, np.int64).reshape(-1, 4), BOX_COST_PX)
    return [tuple(b) for b in merged.tolist()]
