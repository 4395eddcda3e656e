"""Sensor read noise: Gaussian, in DN, rounded to whole DN as the sensor's converter would.

Drawing 77 k normals per frame costs ~0.7 ms in numpy, a third of the frame budget, so a small
bank of noise frames is drawn once from the run's generator and every frame takes a random
crop, shift and sign of one of them (8 x 33 x 33 x 2 = 17 k distinct fields; any one pixel's
values over time stay Gaussian and independent enough for a background model).
"""

from __future__ import annotations

import cv2
import numpy as np

from citysim.config.scenario import EnvironmentSpec
from citysim.render.canvas import Canvas
from citysim.render.effects.common import CameraEffect, EffectFrame

NOISE_BANK_FRAMES = 8
NOISE_SHIFT_PX = 32
_MASK64 = (1 << 64) - 1


class SensorNoise:
    """Additive Gaussian read noise with standard deviation ``std_dn`` (DN), rounded to whole DN."""

    def __init__(
        self, rng: np.random.Generator, height_px: int, width_px: int, std_dn: float
    ) -> None:
        self.std_dn = std_dn
        shape = (NOISE_BANK_FRAMES, height_px + NOISE_SHIFT_PX, width_px + NOISE_SHIFT_PX)
        dn = np.clip(np.rint(rng.standard_normal(shape, dtype=np.float32) * std_dn), -255, 255)
        # signed noise as two saturating uint8 steps (add the positive part, subtract the
        # negative): exact, since a pixel's noise has one sign, and far cheaper than a
        # mixed-type weighted sum
        self.up = np.maximum(dn, 0).astype(np.uint8)
        self.down = np.maximum(-dn, 0).astype(np.uint8)
        self.shape = (height_px, width_px)

    @staticmethod
    def pick(rng: np.random.Generator) -> tuple[int, int, int, int]:
        """A random (bank frame, row shift, column shift, sign) from ``rng``."""
        return tuple(
            rng.integers((NOISE_BANK_FRAMES, NOISE_SHIFT_PX + 1, NOISE_SHIFT_PX + 1, 2)).tolist()
        )

    @staticmethod
    def pick_for(seed: int, frame_index: int) -> tuple[int, int, int, int]:
        """The (bank frame, row shift, column shift, sign) of frame ``frame_index``: a
        splitmix64 hash of the seed and index (a generator per frame costs more than the
        noise itself)."""
        x = (seed + (frame_index + 1) * 0x9E3779B97F4A7C15) & _MASK64
        x = ((x ^ (x >> 30)) * 0xBF58476D1CE4E5B9) & _MASK64
        x = ((x ^ (x >> 27)) * 0x94D049BB133111EB) & _MASK64
        x ^= x >> 31
        out = []
        for n in (NOISE_BANK_FRAMES, NOISE_SHIFT_PX + 1, NOISE_SHIFT_PX + 1, 2):
            x, r = divmod(x, n)
            out.append(r)
        return tuple(out)

    def apply(self, frame_u8: np.ndarray, pick: tuple[int, int, int, int]) -> np.ndarray:
        """``frame_u8`` plus the noise field ``pick`` (see ``pick``): a fresh array."""
        b, dy, dx, sign = pick
        h, w = self.shape
        up, down = (self.up, self.down) if sign else (self.down, self.up)
        out = cv2.add(frame_u8, up[b, dy : dy + h, dx : dx + w])
        return cv2.subtract(out, down[b, dy : dy + h, dx : dx + w], dst=out)


class Noise(CameraEffect):
    """The sensor's noise on every frame (``EnvironmentSpec.sensor_noise_std_dn``; 0: none)."""

    def __init__(self, noise: SensorNoise) -> None:
        self.noise = noise

    @classmethod
    def build(cls, environment: EnvironmentSpec, canvas: Canvas, rng: np.random.Generator) -> Noise | None:
        if environment.sensor_noise_std_dn <= 0.0:
            return None
        cam = canvas.camera
        return cls(SensorNoise(rng, cam.height_px, cam.width_px, environment.sensor_noise_std_dn))

    def filter(self, frame_u8: np.ndarray, frame: EffectFrame) -> np.ndarray:
        if frame.frame_index is None:
            pick = self.noise.pick(frame.rng)
        else:
            pick = self.noise.pick_for(frame.frame_seed, frame.frame_index)
        return self.noise.apply(frame_u8, pick)
