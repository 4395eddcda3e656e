"""Lights that move or switch: what agents carry, glare blobs, lamp heads.

* ``BEAMS``: the lights agents carry, by name (``AgentKind.beam``: vehicles
  carry headlights, cyclists a bike lamp, pedestrians a flashlight); a lit
  agent (``AgentState.light_on``) shows its kind's, and its spot on the ground
  is drawn by ``citysim.render.spots``.
* The lamp itself, when it faces the camera, is a bright blob (a Gaussian of
  the lamp's apparent size plus glow) whose brightness falls with the square
  of its distance; from behind, vehicles show dim tail lights.
* Street lamps that are on show their luminaire as a blob too.
* On a wet road (rain) every blob also has its reflection: a streak from the
  ground below the light down to the image of its mirror point under the road.

An agent's beam is its kind's (``beam_of``). Conventions: canvas
pixels (``citysim.render.canvas``), world frame of docs/design/architecture.md, radiance in
linear full-scale units; lamp offsets are (forward, left, up) m in the agent's
frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

from citysim.config.kinds import AGENT_KINDS
from citysim.render.canvas import Canvas, roi_of
from citysim.world.agents import AgentState


@dataclass(frozen=True)
class BeamSpec:
    """One class's carried light. Lamp offsets scale with the agent's length/width."""

    peak_irradiance: float
    centre_m: float  # spot centre ahead of the lamp
    sigma_forward_m: float
    sigma_lateral_m: float
    spread_per_m: float  # lateral widening per metre ahead
    lamps_flz: tuple[
        tuple[float, float, float], ...
    ]  # (fraction of length, fraction of width, up m)
    glare_power: float  # blob radiance x m^2 when facing the camera
    rear_glare_fraction: float  # tail lights, seen from behind
    lamp_size_m: float


#: Carried lights by name (``AgentKind.beam``), shown when an agent's ``light_on``.
BEAMS: dict[str, BeamSpec] = {
    "headlights": BeamSpec(
        1.6, 9.0, 7.0, 1.2, 0.18, ((0.5, 0.35, 0.65), (0.5, -0.35, 0.65)), 300.0, 0.08, 0.18
    ),
    "bike_lamp": BeamSpec(1.1, 4.0, 3.0, 0.6, 0.15, ((0.45, 0.0, 1.0),), 120.0, 0.05, 0.08),
    "flashlight": BeamSpec(0.9, 2.5, 1.6, 0.35, 0.12, ((0.3, -0.5, 1.0),), 60.0, 0.0, 0.06),
}


def beam_of(cls: str) -> BeamSpec | None:
    """The light an agent of kind ``cls`` carries (None: none drawn, or an unknown kind)."""
    kind = AGENT_KINDS.get(cls)
    return None if kind is None or kind.beam is None else BEAMS[kind.beam]


def shows_light(agent: AgentState) -> bool:
    """Whether the agent's light is drawn: switched on, and its kind carries a beam."""
    return agent.light_on and beam_of(agent.cls) is not None
#: Street-lamp luminaire blob radiance x m^2 at level 1.
LAMP_HEAD_GLARE = 500.0
LAMP_HEAD_SIZE_M = 0.4
#: Lens scatter: a halo HALO_SCALE times wider than the blob at HALO_FRACTION of its peak.
HALO_SCALE, HALO_FRACTION = 3.0, 0.08
#: Fainter blobs (radiance) would not show above the noise.
MIN_GLARE_RADIANCE = 2e-3
#: Wet-road reflection strength relative to the blob.
WET_REFLECTION = 0.35


#: Blob widths are cached in steps of 1/BLOB_STEPS_PER_PX px; blobs sit on whole pixels.
BLOB_STEPS_PER_PX = 4
MAX_BLOB_SIGMA_PX = 12.0


@lru_cache(maxsize=512)
def _blob_stamp(sigma_steps: int) -> np.ndarray:
    """A unit-peak glare blob: Gaussian core plus a halo HALO_SCALE times wider, centred."""
    sigma = sigma_steps / BLOB_STEPS_PER_PX
    r = int(math.ceil(3.0 * HALO_SCALE * sigma))
    d2 = (np.arange(-r, r + 1, dtype=np.float64)[None, :] ** 2) + (
        np.arange(-r, r + 1, dtype=np.float64)[:, None] ** 2
    )
    core = -0.5 / sigma**2
    stamp = np.exp(core * d2) + HALO_FRACTION * np.exp((core / HALO_SCALE**2) * d2)
    stamp = stamp.astype(np.float32)
    stamp.flags.writeable = False
    return stamp


def _blob(
    canvas: Canvas, img: np.ndarray, u: float, v: float, sigma_px: float, peak: float
) -> tuple[int, int, int, int] | None:
    """Add a glare blob of core width ``sigma_px`` and peak radiance ``peak`` at the pixel nearest (u, v)."""
    sigma = min(sigma_px, MAX_BLOB_SIGMA_PX)
    stamp = _blob_stamp(max(1, round(sigma * BLOB_STEPS_PER_PX)))
    r = stamp.shape[0] // 2
    cu, cv_ = round(u), round(v)
    x0, y0 = max(cu - r, 0), max(cv_ - r, 0)
    x1, y1 = min(cu + r + 1, canvas.width_px), min(cv_ + r + 1, canvas.height_px)
    if x1 <= x0 or y1 <= y0:
        return None
    part = stamp[y0 - (cv_ - r) : y1 - (cv_ - r), x0 - (cu - r) : x1 - (cu - r)]
    view = img[y0:y1, x0:x1]
    cv2.scaleAdd(part, float(peak), view, dst=view)
    return x0, y0, x1, y1


def _streak(
    canvas: Canvas, img: np.ndarray, u: float, v0: float, v1: float, sigma_px: float, peak: float
) -> tuple[int, int, int, int] | None:
    """A vertical reflection streak from row v0 down to v1, fading with length."""
    if not (np.isfinite(v0) and np.isfinite(v1)) or v1 <= v0:
        return None
    r = int(math.ceil(2.0 * sigma_px)) + 1
    roi = roi_of(np.array([[u - r, v0], [u + r, v1]]), canvas, margin_px=0)
    if roi is None:
        return None
    x0, y0, x1, y1 = roi
    xs = np.arange(x0, x1, dtype=np.float32) - u
    ys = (np.arange(y0, y1, dtype=np.float32) - v0) / max(v1 - v0, 1.0)
    g = np.exp(-(xs[None, :] ** 2) / (2.0 * sigma_px**2)) * np.clip(1.0 - ys[:, None], 0.0, 1.0)
    img[y0:y1, x0:x1] += peak * g
    return roi


def glare(
    canvas: Canvas,
    img: np.ndarray,
    occluder_depth: np.ndarray,
    points_m: np.ndarray,
    power: np.ndarray,
    size_m: np.ndarray,
    wet: bool,
) -> list[tuple[int, int, int, int]]:
    """Blobs for light sources at ``points_m`` (N, 3) with radiance x m^2 ``power`` (N,);
    sources hidden behind a nearer standing surface are left out. Returns the canvas boxes
    drawn on."""
    if len(points_m) == 0:
        return []
    cam = canvas.camera
    cam_pts = (points_m - cam.position_m) @ cam.rotation_world_to_cam.T
    dist = np.sqrt(np.einsum("ij,ij->i", cam_pts, cam_pts))
    z = np.maximum(cam_pts[:, 2], 1e-3)
    u = cam.fx_px * cam_pts[:, 0] / z + (cam.cx_px - canvas.x0_px)
    v = cam.fy_px * cam_pts[:, 1] / z + (cam.cy_px - canvas.y0_px)
    peak = power / np.maximum(dist**2, 0.25)
    sigma = np.maximum(0.7, cam.fx_px * size_m / z / 2.0)
    h, w = canvas.shape
    show = (cam_pts[:, 2] > 0.05) & (peak >= MIN_GLARE_RADIANCE)
    show &= (u > -3.0 * HALO_SCALE * sigma) & (u < w + 3.0 * HALO_SCALE * sigma)
    show &= (v > -3.0 * HALO_SCALE * sigma) & (v < h + 3.0 * HALO_SCALE * sigma)
    mirrors = None
    if wet and show.any():
        ground = points_m * np.array([1.0, 1.0, 0.0])
        mirrors = (
            canvas.project(ground)[:, 1],
            canvas.project(points_m * np.array([1.0, 1.0, -1.0]))[:, 1],
        )
    boxes = []
    shown = np.flatnonzero(show)
    rows = zip(
        shown.tolist(),
        u[shown].tolist(),
        v[shown].tolist(),
        dist[shown].tolist(),
        sigma[shown].tolist(),
        peak[shown].tolist(),
        strict=True,
    )
    for i, ui, vi, di, si, pi in rows:
        col, row = round(ui), round(vi)
        if 0 <= col < w and 0 <= row < h and occluder_depth[row, col] < di - 0.3:
            continue
        boxes.append(_blob(canvas, img, ui, vi, si, pi))
        if mirrors is not None:
            boxes.append(
                _streak(
                    canvas,
                    img,
                    u[i],
                    mirrors[0][i],
                    mirrors[1][i],
                    sigma[i],
                    WET_REFLECTION * peak[i],
                )
            )
    return [b for b in boxes if b is not None]


def agent_glare_sources(
    canvas: Canvas, agents: list[AgentState], ambient_light: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Light sources carried by lit agents: (points (N, 3), power (N,), size (N,)).

    A lamp shines at the camera as cos^2 of the angle between its heading and
    the camera; from behind, vehicles show their tail lights (a fraction).
    """
    lit = [(a, beam_of(a.cls)) for a in agents if shows_light(a)]
    if not lit:
        return np.zeros((0, 3)), np.zeros(0), np.zeros(0)
    rows = np.array(
        [
            (
                a.x_m,
                a.y_m,
                a.heading_rad,
                a.length_m,
                a.width_m,
                f,
                lat,
                z,
                spec.glare_power,
                spec.rear_glare_fraction,
                spec.lamp_size_m,
            )
            for a, spec in lit
            for f, lat, z in spec.lamps_flz
        ]
    )
    x, y, heading, length, width, f_frac, l_frac, z, glare_power, rear, size = rows.T
    c, s = np.cos(heading), np.sin(heading)
    px = x + c * f_frac * length - s * l_frac * width
    py = y + s * f_frac * length + c * l_frac * width
    cam_xy = canvas.camera.position_m[:2]
    to_x, to_y = cam_xy[0] - px, cam_xy[1] - py
    facing = (to_x * c + to_y * s) / np.maximum(np.hypot(to_x, to_y), 1e-9)
    strength = np.where(facing > 0.0, 1.0, rear) * facing**2
    gain = 1.0 - 0.8 * ambient_light
    return np.column_stack([px, py, z]), gain * glare_power * strength, size
