"""Lights that move or switch: headlight and flashlight spots, glare blobs, lamp heads.

* A lit agent (``AgentState.light_on``; vehicles and cyclists carry
  headlights, pedestrians a flashlight) throws a spot on the ground ahead of
  it: ``E = peak * exp(-((f - centre)/sigma_f)^2) * exp(-(l / (sigma_l + spread * f))^2)``
  for ground points ``f`` m ahead of and ``l`` m beside the lamp, zero behind
  it. Only pixels that see the ground get it (the spot lands before the agents
  are drawn, so they hide it).
* The lamp itself, when it faces the camera, is a bright blob (a Gaussian of
  the lamp's apparent size plus glow) whose brightness falls with the square
  of its distance; from behind, vehicles show dim tail lights.
* Street lamps that are on show their luminaire as a blob too.
* On a wet road (rain) every blob also has its reflection: a streak from the
  ground below the light down to the image of its mirror point under the road.

Kinds are chosen by ``AgentState.cls`` from ``BEAMS``. Conventions: canvas
pixels (``citysim.render_canvas``), world frame of DESIGN.md, radiance in
linear full-scale units; lamp offsets are (forward, left, up) m in the agent's
frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

import cv2
import numpy as np

from citysim.agents import AgentState
from citysim.render_background import StaticScene
from citysim.render_canvas import Canvas, clip_solid_near, roi_of


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


#: AgentState.cls -> its light when ``light_on``.
BEAMS: dict[str, BeamSpec] = {
    "vehicle": BeamSpec(
        1.6, 9.0, 7.0, 1.2, 0.18, ((0.5, 0.35, 0.65), (0.5, -0.35, 0.65)), 300.0, 0.08, 0.18
    ),
    "cyclist": BeamSpec(1.1, 4.0, 3.0, 0.6, 0.15, ((0.45, 0.0, 1.0),), 120.0, 0.05, 0.08),
    "pedestrian": BeamSpec(0.9, 2.5, 1.6, 0.35, 0.12, ((0.3, -0.5, 1.0),), 60.0, 0.0, 0.06),
}
#: Street-lamp luminaire blob radiance x m^2 at level 1.
LAMP_HEAD_GLARE = 500.0
LAMP_HEAD_SIZE_M = 0.4
#: Lens scatter: a halo HALO_SCALE times wider than the blob at HALO_FRACTION of its peak.
HALO_SCALE, HALO_FRACTION = 3.0, 0.08
#: Fainter blobs (radiance) would not show above the noise.
MIN_GLARE_RADIANCE = 2e-3
#: Wet-road reflection strength relative to the blob.
WET_REFLECTION = 0.35


def _lamp_points(agent: AgentState, spec: BeamSpec) -> np.ndarray:
    c, s = math.cos(agent.heading_rad), math.sin(agent.heading_rad)
    out = []
    for f_frac, l_frac, z in spec.lamps_flz:
        f, lat = f_frac * agent.length_m, l_frac * agent.width_m
        out.append([agent.x_m + c * f - s * lat, agent.y_m + s * f + c * lat, z])
    return np.array(out)


SPOT_TEXELS_FORWARD, SPOT_TEXELS_LATERAL = 96, 48


def _spot_extent_m(spec: BeamSpec) -> tuple[float, float]:
    """(forward reach, half width) of the ground box that holds the spot, m."""
    f_far = spec.centre_m + 2.0 * spec.sigma_forward_m
    return f_far, 2.0 * (spec.sigma_lateral_m + spec.spread_per_m * f_far)


@cache
def spot_texture(spec: BeamSpec) -> np.ndarray:
    """The spot's irradiance (full-scale units) on a ground grid: rows run forward from the
    lamp (0 .. reach), columns across it (-half width .. +half width), texel centres on the grid."""
    f_far, half_w = _spot_extent_m(spec)
    f = (np.arange(SPOT_TEXELS_FORWARD) + 0.5) * (f_far / SPOT_TEXELS_FORWARD)
    lat = (np.arange(SPOT_TEXELS_LATERAL) + 0.5) * (2.0 * half_w / SPOT_TEXELS_LATERAL) - half_w
    width = spec.sigma_lateral_m + spec.spread_per_m * f
    e = np.exp(-(((f - spec.centre_m) / spec.sigma_forward_m) ** 2))[:, None] * np.exp(
        -((lat[None, :] / width[:, None]) ** 2)
    )
    e *= np.clip(f / 0.5, 0.0, 1.0)[:, None]  # the light starts at the lamp, not before it
    return (spec.peak_irradiance * e).astype(np.float32)


def add_ground_spot(
    scene: StaticScene, img: np.ndarray, agent: AgentState, spec: BeamSpec, gain: float
) -> None:
    """Add the agent's light spot to the visible ground of ``img`` (radiance).

    The canvas is an ideal pinhole image, so ground plane -> canvas is a
    homography: the precomputed spot texture is warped onto the canvas with
    ``cv2.warpPerspective`` and weighted by each pixel's ground reflectance
    (zero where the pixel does not see the ground).
    """
    canvas = scene.canvas
    cam = canvas.camera
    origin = _lamp_points(agent, spec)[:, :2].mean(axis=0)
    fwd = np.array([math.cos(agent.heading_rad), math.sin(agent.heading_rad)])
    left = np.array([-fwd[1], fwd[0]])
    f_far, half_w = _spot_extent_m(spec)
    # texel (col, row) -> ground (x, y, 1)
    df, dl = f_far / SPOT_TEXELS_FORWARD, 2.0 * half_w / SPOT_TEXELS_LATERAL
    start = origin - half_w * left + 0.5 * df * fwd + 0.5 * dl * left
    tex_to_ground = np.array(
        [
            [dl * left[0], df * fwd[0], start[0]],
            [dl * left[1], df * fwd[1], start[1]],
            [0.0, 0.0, 1.0],
        ]
    )
    rot = cam.rotation_world_to_cam
    ground_to_cam = np.column_stack([rot[:, 0], rot[:, 1], -rot @ cam.position_m])
    shift = np.array([[1.0, 0.0, -canvas.x0_px], [0.0, 1.0, -canvas.y0_px], [0.0, 0.0, 1.0]])
    tex_to_canvas = shift @ cam.intrinsic_matrix @ ground_to_cam @ tex_to_ground

    # the spot's ground box, cut where it leaves the camera's view of the ground (behind it or under it)
    box_tex = np.array(
        [
            [x, y, 1.0]
            for x in (-0.5, SPOT_TEXELS_LATERAL - 0.5)
            for y in (-0.5, SPOT_TEXELS_FORWARD - 0.5)
        ]
    )
    box_world = np.column_stack([(box_tex @ tex_to_ground.T)[:, :2], np.zeros(4)])
    near = clip_solid_near(cam.world_to_cam(box_world), 0.8 * scene.nearest_ground_cam_z_m)
    if near is None:
        return
    roi = roi_of(canvas.cam_to_canvas(near), canvas)
    if roi is None:
        return
    x0, y0, x1, y1 = roi
    rho = scene.ground_reflectance[y0:y1, x0:x1]
    # the spot is smooth: warp it at half resolution (a quarter of the perspective divisions)
    hw, hh = (x1 - x0 + 1) // 2, (y1 - y0 + 1) // 2
    to_half = np.array(
        [[0.5, 0.0, 0.5 * (0.5 - x0) - 0.5], [0.0, 0.5, 0.5 * (0.5 - y0) - 0.5], [0.0, 0.0, 1.0]]
    )
    half = cv2.warpPerspective(
        spot_texture(spec),
        to_half @ tex_to_canvas,
        (hw, hh),
        flags=cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT,
    )
    e = cv2.resize(half, (2 * hw, 2 * hh), interpolation=cv2.INTER_LINEAR)[: y1 - y0, : x1 - x0]
    img[y0:y1, x0:x1] += gain * rho * e


def _blob(
    canvas: Canvas, img: np.ndarray, u: float, v: float, sigma_px: float, peak: float
) -> None:
    """Add a glare blob: a Gaussian core of ``sigma_px`` and a faint halo three times wider."""
    r = int(math.ceil(3.0 * HALO_SCALE * sigma_px))
    x0, y0 = max(int(u) - r, 0), max(int(v) - r, 0)
    x1, y1 = min(int(u) + r + 2, canvas.width_px), min(int(v) + r + 2, canvas.height_px)
    if x1 <= x0 or y1 <= y0:
        return
    d2 = (np.arange(x0, x1, dtype=np.float32) - u)[None, :] ** 2 + (
        np.arange(y0, y1, dtype=np.float32) - v
    )[:, None] ** 2
    core = -0.5 / sigma_px**2
    g = np.exp(core * d2) + HALO_FRACTION * np.exp((core / HALO_SCALE**2) * d2)
    view = img[y0:y1, x0:x1]
    cv2.scaleAdd(g.astype(np.float32, copy=False), float(peak), view, dst=view)


def _streak(
    canvas: Canvas, img: np.ndarray, u: float, v0: float, v1: float, sigma_px: float, peak: float
) -> None:
    """A vertical reflection streak from row v0 down to v1, fading with length."""
    if not (np.isfinite(v0) and np.isfinite(v1)) or v1 <= v0:
        return
    r = int(math.ceil(2.0 * sigma_px)) + 1
    roi = roi_of(np.array([[u - r, v0], [u + r, v1]]), canvas, margin_px=0)
    if roi is None:
        return
    x0, y0, x1, y1 = roi
    xs = np.arange(x0, x1, dtype=np.float32) - u
    ys = (np.arange(y0, y1, dtype=np.float32) - v0) / max(v1 - v0, 1.0)
    g = np.exp(-(xs[None, :] ** 2) / (2.0 * sigma_px**2)) * np.clip(1.0 - ys[:, None], 0.0, 1.0)
    img[y0:y1, x0:x1] += peak * g


def glare(
    canvas: Canvas,
    img: np.ndarray,
    occluder_depth: np.ndarray,
    points_m: np.ndarray,
    power: np.ndarray,
    size_m: np.ndarray,
    wet: bool,
) -> None:
    """Blobs for light sources at ``points_m`` (N, 3) with radiance x m^2 ``power`` (N,)."""
    if len(points_m) == 0:
        return
    cam = canvas.camera
    uv = canvas.project(points_m)
    cam_pts = cam.world_to_cam(points_m)
    dist = np.linalg.norm(points_m - cam.position_m, axis=1)
    h, w = canvas.shape
    mirrors = None
    if wet:
        ground = points_m * np.array([1.0, 1.0, 0.0])
        mirrors = (canvas.project(ground), canvas.project(points_m * np.array([1.0, 1.0, -1.0])))
    for i in range(len(points_m)):
        u, v = uv[i]
        if not np.isfinite(u) or power[i] <= 0.0:
            continue
        col, row = int(round(u)), int(round(v))
        if 0 <= col < w and 0 <= row < h and occluder_depth[row, col] < dist[i] - 0.3:
            continue
        sigma = max(0.7, cam.fx_px * size_m[i] / max(cam_pts[i, 2], 1e-3) / 2.0)
        peak = float(power[i] / max(dist[i] ** 2, 0.25))
        if peak < MIN_GLARE_RADIANCE:
            continue
        _blob(canvas, img, u, v, sigma, peak)
        if mirrors is not None:
            _streak(
                canvas, img, u, mirrors[0][i, 1], mirrors[1][i, 1], sigma, WET_REFLECTION * peak
            )


def agent_glare_sources(
    canvas: Canvas, agents: list[AgentState], ambient_light: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Light sources carried by lit agents: (points (N, 3), power (N,), size (N,))."""
    pts, power, size = [], [], []
    cam_xy = canvas.camera.position_m[:2]
    gain = 1.0 - 0.8 * ambient_light
    for agent in agents:
        spec = BEAMS.get(agent.cls)
        if spec is None or not agent.light_on:
            continue
        lamps = _lamp_points(agent, spec)
        fwd = np.array([math.cos(agent.heading_rad), math.sin(agent.heading_rad)])
        to_cam = cam_xy - lamps[:, :2]
        facing = (to_cam @ fwd) / np.maximum(np.linalg.norm(to_cam, axis=1), 1e-9)
        strength = np.where(facing > 0.0, facing**2, spec.rear_glare_fraction * facing**2)
        pts.append(lamps)
        power.append(gain * spec.glare_power * strength)
        size.append(np.full(len(lamps), spec.lamp_size_m))
    if not pts:
        return np.zeros((0, 3)), np.zeros(0), np.zeros(0)
    return np.concatenate(pts), np.concatenate(power), np.concatenate(size)
