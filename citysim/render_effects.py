"""Things in front of the scene that are not targets, and the sensor's noise.

* ``SensorNoise``: Gaussian read noise in DN. Drawing 77 k normals per frame
  costs ~0.7 ms in numpy, a third of the frame budget, so a small bank of
  noise frames is drawn once from the run's generator and every frame takes a
  random crop, shift and sign of one of them (8 x 33 x 33 x 2 = 17 k distinct
  fields; any one pixel's values over time stay Gaussian and independent
  enough for a background model).
* ``Rain``: drops close to the lens, lit by the emitter and smeared by the
  exposure into short near-vertical streaks.
* ``Insects``: moths at the emitter, 0.15-1.5 m from the lens: big, bright,
  out-of-focus blobs that cross the view fast (a classic false trigger).
  They arrive as a Poisson process and wander (an Ornstein-Uhlenbeck
  velocity) until they leave the view or their time is up.

All randomness comes from the ``numpy.random.Generator`` given to the
renderer, in a fixed order, so a seed fixes every frame. Conventions: canvas
pixels of ``citysim.render_canvas``; camera frame x right, y down, z forward
(m); radiance in linear full-scale units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from citysim.render_canvas import Canvas, roi_of

NOISE_BANK_FRAMES = 8
NOISE_SHIFT_PX = 32
#: The bank stores noise in int8 at this many steps per standard deviation.
NOISE_STEPS_PER_STD = 16.0


class SensorNoise:
    """Additive Gaussian read noise with standard deviation ``std_dn`` (DN)."""

    def __init__(
        self, rng: np.random.Generator, height_px: int, width_px: int, std_dn: float
    ) -> None:
        self.std_dn = std_dn
        shape = (NOISE_BANK_FRAMES, height_px + NOISE_SHIFT_PX, width_px + NOISE_SHIFT_PX)
        bank = rng.standard_normal(shape, dtype=np.float32) * NOISE_STEPS_PER_STD
        self.bank = np.clip(np.round(bank), -127, 127).astype(np.int8)
        self.shape = (height_px, width_px)

    def apply(self, frame_u8: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        b, dy, dx, sign = rng.integers(
            (NOISE_BANK_FRAMES, NOISE_SHIFT_PX + 1, NOISE_SHIFT_PX + 1, 2)
        )
        h, w = self.shape
        crop = self.bank[b, dy : dy + h, dx : dx + w]
        scale = (1.0 if sign else -1.0) * self.std_dn / NOISE_STEPS_PER_STD
        return cv2.addWeighted(frame_u8, 1.0, crop, scale, 0.0, dtype=cv2.CV_8U)


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


@dataclass
class Insect:
    pos_cam_m: np.ndarray  # (3,) camera frame
    vel_mps: np.ndarray  # (3,)
    until_s: float


INSECT_NEAR_M, INSECT_FAR_M = 0.15, 1.5
INSECT_SPEED_MPS = 1.2
INSECT_SIZE_M = 0.012
#: How far out of focus the lens is at 1 m, px of blur per (1/z) m^-1.
DEFOCUS_PX_M = 1.2
INSECT_RADIANCE_M2 = 0.3


class Insects:
    """Moths in front of the lens; their state advances with every rendered frame."""

    def __init__(self, per_min: float) -> None:
        self.rate_per_s = per_min / 60.0
        self.active: list[Insect] = []
        self.last_t_s: float | None = None

    def _spawn(self, canvas: Canvas, t_s: float, rng: np.random.Generator) -> Insect:
        cam = canvas.camera
        z = rng.uniform(INSECT_NEAR_M, INSECT_FAR_M)
        u = rng.uniform(0.0, cam.width_px)
        v = rng.uniform(0.0, cam.height_px)
        pos = np.array([(u - cam.cx_px) / cam.fx_px * z, (v - cam.cy_px) / cam.fy_px * z, z])
        vel = rng.normal(0.0, INSECT_SPEED_MPS, 3) * np.array([1.0, 1.0, 0.3])
        return Insect(pos, vel, t_s + rng.uniform(0.5, 4.0))

    def draw(
        self,
        canvas: Canvas,
        img: np.ndarray,
        t_s: float,
        exposure_s: float,
        emitter_power: float,
        ambient_light: float,
        rng: np.random.Generator,
    ) -> None:
        dt = 1.0 / canvas.camera.fps if self.last_t_s is None else max(t_s - self.last_t_s, 0.0)
        self.last_t_s = t_s
        if self.rate_per_s <= 0.0 and not self.active:
            return
        alive = []
        for bug in self.active:
            # Ornstein-Uhlenbeck velocity: erratic, but with a typical speed
            theta = 2.0
            bug.vel_mps = bug.vel_mps * math.exp(-theta * dt) + rng.normal(
                0.0, INSECT_SPEED_MPS * math.sqrt(1.0 - math.exp(-2.0 * theta * dt)), 3
            ) * np.array([1.0, 1.0, 0.3])
            bug.pos_cam_m = bug.pos_cam_m + bug.vel_mps * dt
            if t_s < bug.until_s and INSECT_NEAR_M * 0.5 < bug.pos_cam_m[2] < INSECT_FAR_M * 2:
                alive.append(bug)
        for _ in range(rng.poisson(self.rate_per_s * dt)):
            alive.append(self._spawn(canvas, t_s, rng))
        self.active = alive
        for bug in alive:
            self._draw_one(canvas, img, bug, exposure_s, emitter_power, ambient_light)

    def _draw_one(
        self,
        canvas: Canvas,
        img: np.ndarray,
        bug: Insect,
        exposure_s: float,
        emitter_power: float,
        ambient_light: float,
    ) -> None:
        now = bug.pos_cam_m
        before = now - bug.vel_mps * exposure_s
        if before[2] <= 0.05:
            before = now
        uv = canvas.cam_to_canvas(np.stack([now, before]))
        z = now[2]
        core_px = max(canvas.camera.fx_px * INSECT_SIZE_M / z, 1.0)
        sigma_px = max(DEFOCUS_PX_M / z, 0.5)
        pad = int(math.ceil(core_px + 3.0 * sigma_px)) + 1
        roi = roi_of(uv, canvas, margin_px=pad)
        if roi is None:
            return
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
            tuple(int(c) for c in a),
            tuple(int(c) for c in b),
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
