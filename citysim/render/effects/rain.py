"""Rain: drops close to the lens, lit by the emitter and smeared by the exposure into short
near-vertical streaks."""

from __future__ import annotations

import cv2
import numpy as np

from citysim.config.scenario import EnvironmentSpec
from citysim.render.canvas import Canvas
from citysim.render.effects.common import Box, CameraEffect, EffectFrame

#: Terminal speed of rain drops, m/s.
RAIN_FALL_MPS = 6.0
RAIN_NEAR_M, RAIN_FAR_M = 0.3, 5.0
#: Drop radiance x m^2 under the emitter (small, out of focus, but close).
RAIN_RADIANCE_M2 = 0.02


def draw_rain(
    canvas: Canvas,
    img: np.ndarray,
    n_drops: int,
    exposure_s: float,
    emitter_power: float,
    ambient_light: float,
    rng: np.random.Generator,
) -> None:
    """Add ``n_drops`` streaks (random depth and position) to ``img``."""
    if n_drops <= 0:
        return
    cam = canvas.camera
    u = rng.uniform(0.0, canvas.width_px, n_drops)
    v = rng.uniform(0.0, canvas.height_px, n_drops)
    z = RAIN_FAR_M / (
        1.0 + rng.uniform(0.0, RAIN_FAR_M / RAIN_NEAR_M - 1.0, n_drops)
    )  # more drops far
    slant = rng.normal(0.0, 0.08, n_drops)
    # a drop falls straight down in the world; its image direction follows the world's down axis
    down_cam = cam.rotation_world_to_cam @ np.array([0.0, 0.0, -1.0])
    fall_m = RAIN_FALL_MPS * max(exposure_s, 1e-3)
    du = cam.fx_px * (down_cam[0] + slant) * fall_m / z
    dv = cam.fy_px * down_cam[1] * fall_m / z
    radiance = (
        RAIN_RADIANCE_M2 * (emitter_power * (1.0 - ambient_light) + 20.0 * ambient_light) / z**2
    )
    radiance = np.minimum(radiance / np.maximum(np.hypot(du, dv), 1.0) * 4.0, 0.6)
    layer = np.zeros(canvas.shape, np.float32)
    pts = np.stack([np.column_stack([u, v]), np.column_stack([u + du, v + dv])], axis=1)
    fixed = np.round(pts * 16).astype(np.int32)
    levels = np.quantile(radiance, [0.0, 0.5, 0.9, 1.0])
    for lo, hi in zip(levels[:-1], levels[1:], strict=True):
        sel = (radiance >= lo) & (radiance <= hi)
        if sel.any():
            cv2.polylines(
                layer, list(fixed[sel]), False, float(radiance[sel].mean()), 1, cv2.LINE_8, 4
            )
    cv2.add(img, layer, dst=img)


class Rain(CameraEffect):
    """``EnvironmentSpec.rain_drops_per_frame`` streaks per frame when the weather is rain."""

    def __init__(self, drops_per_frame: int) -> None:
        self.drops_per_frame = drops_per_frame

    @classmethod
    def build(cls, environment: EnvironmentSpec, canvas: Canvas, rng: np.random.Generator) -> Rain | None:
        drops = environment.rain_drops_per_frame if environment.weather == "rain" else 0
        return cls(drops) if drops > 0 else None

    def draw(self, frame: EffectFrame) -> list[Box]:
        draw_rain(frame.canvas, frame.img, self.drops_per_frame, frame.exposure_s, frame.emitter_power,
                  frame.ambient_light, frame.frame_rng())  # fmt: skip
        canvas = frame.canvas
        return [(0, 0, canvas.width_px, canvas.height_px)]
