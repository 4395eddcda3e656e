"""Insects at the emitter: moths 0.15-1.5 m from the lens, big, bright, out-of-focus blobs that
cross the view fast (a classic false trigger). They arrive as a Poisson process, drift and loop,
and vanish when their time is up; the process is a pure function of time for its seed."""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from citysim.config.scenario import EnvironmentSpec
from citysim.render.canvas import Canvas, roi_of
from citysim.render.effects.common import Box, CameraEffect, EffectFrame

INSECT_NEAR_M, INSECT_FAR_M = 0.15, 1.5
INSECT_DRIFT_MPS = 0.6
INSECT_WANDER_M = 0.15
INSECT_LIFE_S = (0.5, 4.0)
INSECT_SIZE_M = 0.012
#: How far out of focus the lens is at 1 m, px of blur per (1/z) m^-1.
DEFOCUS_PX_M = 1.2
INSECT_RADIANCE_M2 = 0.3
#: Insects are drawn per time window from a generator seeded by (seed, window): any frame can
#: be rendered alone, in any order, and shows the same insects.
INSECT_WINDOW_S = 2.0


@dataclass(frozen=True)
class Insect:
    """One moth: a drift plus a looping wander (three sines), camera frame, m and s."""

    born_s: float
    dies_s: float
    start_m: np.ndarray  # (3,)
    drift_mps: np.ndarray  # (3,)
    wander_m: np.ndarray  # (3,) amplitudes
    wander_hz: np.ndarray  # (3,)
    wander_rad: np.ndarray  # (3,) phases

    def position_m(self, t_s: float) -> np.ndarray:
        age = t_s - self.born_s
        loop = np.sin(2.0 * math.pi * self.wander_hz * age + self.wander_rad) - np.sin(
            self.wander_rad
        )
        return self.start_m + self.drift_mps * age + self.wander_m * loop


class Insects:
    """Moths in front of the lens, a Poisson process of ``per_min`` arrivals; a deterministic
    function of time for a given ``seed`` (no state carried between frames)."""

    def __init__(self, per_min: float, seed: int) -> None:
        self.rate_per_s = per_min / 60.0
        self.seed = seed
        self._windows: dict[int, tuple[Insect, ...]] = {}

    def _window(self, canvas: Canvas, w: int) -> tuple[Insect, ...]:
        if w not in self._windows:
            rng = np.random.default_rng([self.seed, w])
            cam = canvas.camera
            out = []
            for _ in range(rng.poisson(self.rate_per_s * INSECT_WINDOW_S)):
                born = (w + rng.random()) * INSECT_WINDOW_S
                z = rng.uniform(INSECT_NEAR_M, INSECT_FAR_M)
                u, v = rng.uniform(0.0, cam.width_px), rng.uniform(0.0, cam.height_px)
                start = np.array(
                    [(u - cam.cx_px) / cam.fx_px * z, (v - cam.cy_px) / cam.fy_px * z, z]
                )
                out.append(
                    Insect(
                        born,
                        born + rng.uniform(*INSECT_LIFE_S),
                        start,
                        rng.normal(0.0, INSECT_DRIFT_MPS, 3) * np.array([1.0, 1.0, 0.3]),
                        INSECT_WANDER_M * rng.uniform(0.3, 1.0, 3) * np.array([1.0, 1.0, 0.3]),
                        rng.uniform(1.0, 3.0, 3),
                        rng.uniform(0.0, 2.0 * math.pi, 3),
                    )
                )
            self._windows[w] = tuple(out)
        return self._windows[w]

    def active(self, canvas: Canvas, t_s: float) -> list[Insect]:
        """The insects alive at time t (s >= 0)."""
        if self.rate_per_s <= 0.0:
            return []
        last = math.floor(t_s / INSECT_WINDOW_S)
        first = max(math.floor((t_s - INSECT_LIFE_S[1]) / INSECT_WINDOW_S), 0)
        for old in [w for w in self._windows if w < first]:
            del self._windows[old]  # the process only moves forward in the common case: forget
        return [
            bug
            for w in range(first, last + 1)
            for bug in self._window(canvas, w)
            if bug.born_s <= t_s < bug.dies_s
        ]

    def draw(
        self,
        canvas: Canvas,
        img: np.ndarray,
        t_s: float,
        exposure_s: float,
        emitter_power: float,
        ambient_light: float,
    ) -> list[tuple[int, int, int, int]]:
        """Draw the insects alive at time t; returns the canvas boxes drawn on."""
        boxes = []
        for bug in self.active(canvas, t_s):
            now = bug.position_m(t_s)
            before = bug.position_m(max(t_s - exposure_s, bug.born_s))
            if INSECT_NEAR_M * 0.5 < now[2] < INSECT_FAR_M * 2 and before[2] > 0.05:
                box = self._draw_one(canvas, img, now, before, emitter_power, ambient_light)
                if box is not None:
                    boxes.append(box)
        return boxes

    @staticmethod
    def _draw_one(
        canvas: Canvas,
        img: np.ndarray,
        now: np.ndarray,
        before: np.ndarray,
        emitter_power: float,
        ambient_light: float,
    ) -> tuple[int, int, int, int] | None:
        uv = canvas.cam_to_canvas(np.stack([now, before]))
        z = now[2]
        core_px = max(canvas.camera.fx_px * INSECT_SIZE_M / z, 1.0)
        sigma_px = max(DEFOCUS_PX_M / z, 0.5)
        pad = int(math.ceil(core_px + 3.0 * sigma_px)) + 1
        roi = roi_of(uv, canvas, margin_px=pad)
        if roi is None:
            return None
        x0, y0, x1, y1 = roi
        layer = np.zeros((y1 - y0, x1 - x0), np.float32)
        a, b = np.round((uv - [x0, y0]) * 16).astype(np.int32)
        brightness = (
            INSECT_RADIANCE_M2
            * (emitter_power * (1.0 - ambient_light) + 10.0 * ambient_light)
            / z**2
        )
        cv2.line(
            layer,
            (int(a[0]), int(a[1])),
            (int(b[0]), int(b[1])),
            1.0,
            int(round(core_px)),
            cv2.LINE_8,
            4,
        )
        layer = cv2.GaussianBlur(layer, (0, 0), sigma_px)
        # the blob's light is spread by defocus and motion; its total stays the same
        streak_px = max(float(np.hypot(*(uv[0] - uv[1]))), 1.0)
        view = img[y0:y1, x0:x1]
        cv2.scaleAdd(
            layer, float(min(brightness, 50.0) * core_px / (core_px + streak_px)), view, dst=view
        )
        return roi


class InsectsEffect(CameraEffect):
    """``EnvironmentSpec.insects_per_min`` moths crossing the view."""

    def __init__(self, insects: Insects) -> None:
        self.insects = insects

    @classmethod
    def build(cls, environment: EnvironmentSpec, canvas: Canvas, rng: np.random.Generator) -> InsectsEffect:
        # the seed is drawn even on a night without insects, so the renderer's later draws do
        # not depend on whether insects fly
        return cls(Insects(environment.insects_per_min, int(rng.integers(2**63))))

    def draw(self, frame: EffectFrame) -> list[Box]:
        return self.insects.draw(frame.canvas, frame.img, max(frame.t_s, 0.0), frame.exposure_s,
                                 frame.emitter_power, frame.ambient_light)  # fmt: skip
