"""Swaying tree crowns: each crown's wind, and its pre-rendered poses across the sway.

The static background (``citysim.render.background``) builds one ``CrownSprite`` per crown that
the wind moves visibly; each frame shows the pose nearest the wind's offset at that time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from citysim.render.canvas import Canvas
from citysim.render.scenery import Ellipsoid

#: Crown displacement per unit wind speed, m per (m/s).
SWAY_M_PER_MPS = 0.025
#: A swaying crown is pre-rendered in this many positions across its sway.
SWAY_POSES = 9
#: Crowns whose sway moves them less than this in the image (px) are drawn still.
SWAY_MIN_PX = 0.4


@dataclass(frozen=True, eq=False)
class CrownSprite:
    """A swaying tree crown over canvas box ``roi`` (margins for the sway included).

    The sway moves the crown along one image direction, so it is pre-rendered
    in SWAY_POSES positions from one extreme to the other; each frame shows
    the pose nearest the wind's current offset. Per pose: coverage (alpha,
    already cut where nearer static things stand before the crown), radiance
    x alpha without lamps and per lamp at level 1.
    """

    roi: tuple[int, int, int, int]
    near_m: float  # distance to the crown's nearest visible point: its depth for occlusion
    alpha: tuple[np.ndarray, ...]  # per pose
    covered: tuple[np.ndarray, ...]  # per pose, bool: alpha > 1/2 (where it hides what is behind)
    base: tuple[np.ndarray, ...]  # per pose
    pools: tuple[tuple[int, tuple[np.ndarray, ...]], ...]  # (lamp index, per pose)
    freq_hz: float
    phases_rad: tuple[float, float]

    def pose(self, t_s: float) -> int:
        """Index of the pre-rendered pose nearest the sway at time t (a gust-like sum of two sines)."""
        w = 2.0 * math.pi * self.freq_hz * t_s
        s = 0.75 * math.sin(w + self.phases_rad[0]) + 0.25 * math.sin(2.3 * w + self.phases_rad[1])
        return round((s + 1.0) / 2.0 * (len(self.alpha) - 1))


def draw_sway(rng: np.random.Generator) -> tuple[float, float, tuple[float, float]]:
    """One crown's wind: direction (rad from +x), frequency (Hz) and two phases (rad)."""
    angle = float(rng.uniform(-0.4, 0.4))
    freq_hz = float(rng.uniform(0.25, 0.6))
    return angle, freq_hz, (float(rng.uniform(0, 2 * math.pi)), float(rng.uniform(0, 2 * math.pi)))


def sway_px(canvas: Canvas, crown: Ellipsoid, amplitude_m: float) -> float:
    """Largest image motion (px) of the crown's centre when it sways ``amplitude_m``; 0 if unseen."""
    if amplitude_m <= 0.0:
        return 0.0
    c = crown.centre_m
    uv = canvas.project(np.array([c, c + [amplitude_m, 0.0, 0.0], c + [0.0, amplitude_m, 0.0]]))
    if not np.all(np.isfinite(uv)):
        return 0.0
    return float(np.abs(uv[1:] - uv[0]).max())
