"""What every camera effect is given and may do (see the package docstring)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from citysim.render.canvas import Canvas

Box = tuple[int, int, int, int]


@dataclass(frozen=True)
class EffectFrame:
    """One frame as the effects see it: the canvas being drawn (``img``, linear radiance), the
    time, the exposure, the light on the scene, and the frame's random source: the renderer's
    generator in call order, or (with ``frame_index``) a function of the renderer's seed and the
    index, so a frame is the same whichever frames were rendered before it."""

    canvas: Canvas
    img: np.ndarray
    t_s: float
    exposure_s: float
    emitter_power: float
    ambient_light: float
    rng: np.random.Generator
    frame_seed: int
    frame_index: int | None

    def frame_rng(self) -> np.random.Generator:
        if self.frame_index is None:
            return self.rng
        return np.random.default_rng([self.frame_seed, self.frame_index])


class CameraEffect:
    """Base effect: draws nothing, filters nothing."""

    def draw(self, frame: EffectFrame) -> list[Box]:
        """Draw on ``frame.img``; the canvas boxes drawn on (the frame output redoes only those)."""
        return []

    def filter(self, frame_u8: np.ndarray, frame: EffectFrame) -> np.ndarray:
        """The 8-bit frame after this effect (may be a new array)."""
        return frame_u8
