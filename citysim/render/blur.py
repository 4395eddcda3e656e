"""Motion blur of agent layers: line kernels, smears, and grouping agents by their motion.

Over the exposure an agent moves across the image; every pixel sees it for
the fraction of the exposure it covers that pixel. The blur of a layer is
therefore the average of the layer over its positions from now (offset 0)
back to ``(du, dv)`` px ago - a line kernel (``cv2.filter2D``).

Agents near each other whose image motions are nearly equal (within 1 px or
15 %, ``citysim.render.kernels.group_boxes``) share one smear, by their mean motion: the
difference is below what a frame can show.

Conventions: canvas pixels of ``citysim.render.canvas``; ``(du, dv)`` is the
image displacement (px) from the agent's image at time t back to its image at
t - exposure.
"""

from __future__ import annotations

import math
from functools import lru_cache

import cv2
import numpy as np

from citysim.render.kernels import line_kernel

#: Below this image motion over the exposure (px), blur is invisible and skipped.
MIN_BLUR_PX = 0.5
#: Blur kernels are cached on a grid of this many steps per pixel of motion.
KERNEL_STEPS_PER_PX = 4
#: Direct line filters are kept under this many taps; longer smears are done at lower resolution.
MAX_KERNEL_TAPS = 48
#: Agents share one smear when their motions differ by at most this many px ...
SHARED_BLUR_PX = 1.0
#: ... or this fraction of the longer motion.
SHARED_BLUR_FRACTION = 0.15


def _blur_kernel(du_px: float, dv_px: float) -> tuple[np.ndarray, tuple[int, int]]:
    """Line kernel and its anchor for ``cv2.filter2D``: averages the layer over its positions
    from now (offset 0) back to ``(du, dv)`` px ago. The kernel only spans the line's bounding
    box, so a horizontal smear stays a cheap 1-3 row filter."""
    return _line_kernel(round(du_px * KERNEL_STEPS_PER_PX), round(dv_px * KERNEL_STEPS_PER_PX))


@lru_cache(maxsize=4096)
def _line_kernel(du_steps: int, dv_steps: int) -> tuple[np.ndarray, tuple[int, int]]:
    kernel, ax, ay = line_kernel(du_steps / KERNEL_STEPS_PER_PX, dv_steps / KERNEL_STEPS_PER_PX)
    kernel.flags.writeable = False
    return kernel, (ax, ay)


def _level(du_px: float, dv_px: float) -> int:
    """How many times a layer is halved before smearing by (du, dv): long diagonal smears
    would need big 2-D kernels; their smear is wider than the detail lost."""
    level = 0
    while (abs(du_px) / 2**level + 2) * (abs(dv_px) / 2**level + 2) > MAX_KERNEL_TAPS:
        level += 1
    return level


def _smear(layer: np.ndarray, du_px: float, dv_px: float) -> np.ndarray:
    """Motion blur of ``layer`` (H, W float32) by the image motion (du, dv) px.

    Layers are halved in resolution until the kernel has at most
    MAX_KERNEL_TAPS taps, smeared, and scaled back (``_level``).
    """
    level = _level(du_px, dv_px)
    kernel, anchor = _blur_kernel(du_px / 2**level, dv_px / 2**level)
    if level == 0:
        return cv2.filter2D(layer, -1, kernel, anchor=anchor, borderType=cv2.BORDER_CONSTANT)
    h, w = layer.shape
    f = 2**level
    hs, ws = (h + f - 1) // f, (w + f - 1) // f
    # pad to whole f x f blocks so down- and up-scaling keep pixel centres aligned
    padded = cv2.copyMakeBorder(layer, 0, hs * f - h, 0, ws * f - w, cv2.BORDER_CONSTANT, value=0.0)
    small = cv2.resize(padded, (ws, hs), interpolation=cv2.INTER_AREA)
    small = cv2.filter2D(small, -1, kernel, anchor=anchor, borderType=cv2.BORDER_CONSTANT)
    return cv2.resize(small, (ws * f, hs * f), interpolation=cv2.INTER_LINEAR)[:h, :w]


def stacked_layers(h: int, w: int, du_px: float, dv_px: float) -> tuple[np.ndarray, int]:
    """An empty (rows, w) float32 buffer holding two (h, w) layers for one ``smear_stacked``
    call: the first at rows [0, h), the second from the returned row; the rows between are
    zero and wide enough that the smear never carries light from one layer to the other."""
    f = 2 ** _level(du_px, dv_px)
    gap = f * (math.ceil(abs(dv_px) / f) + 3)
    start = f * math.ceil((h + gap) / f)  # on a block boundary: both layers scale alike
    buf = np.empty((start + h, w), np.float32)
    buf[h:start] = 0.0
    return buf, start


def smear_stacked(buf: np.ndarray, du_px: float, dv_px: float) -> np.ndarray:
    """``_smear`` of both layers of a ``stacked_layers`` buffer in one filter pass."""
    return _smear(buf, du_px, dv_px)
