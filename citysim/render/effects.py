"""Things in front of the scene that are not targets, and the sensor's noise.

* ``SensorNoise``: Gaussian read noise in DN. Drawing 77 k normals per frame
  costs ~0.7 ms in numpy, a third of the frame budget, so a small bank of
  noise frames is drawn once from the run's generator and every frame takes a
  random crop, shift and sign of one of them (8 x 33 x 33 x 2 = 17 k distinct
  fields; any one pixel's values over time stay Gaussian and independent
  enough for a background model). The noise is rounded to whole DN, as the
  sensor's converter would.
* ``Rain``: drops close to the lens, lit by the emitter and smeared by the
  exposure into short near-vertical streaks.
* ``Insects``: moths at the emitter, 0.15-1.5 m from the lens: big, bright,
  out-of-focus blobs that cross the view fast (a classic false trigger).
  They arrive as a Poisson process, drift and loop, and vanish when their
  time is up; the process is a pure function of time for its seed.

All randomness comes from the ``numpy.random.Generator`` given to the
renderer (or generators seeded from it), so a seed fixes every frame. Conventions: canvas
pixels of ``citysim.render.canvas``; camera frame x right, y down, z forward
(m); radiance in linear full-scale units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from citysim.render.canvas import Canvas, roi_of

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
