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
from functools import cache, lru_cache

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


@cache
def spot_extent_m(spec: BeamSpec) -> tuple[float, float]:
    """(forward reach, half width) of the ground box that holds the spot, m."""
    f_far = spec.centre_m + 2.0 * spec.sigma_forward_m
    return f_far, 1.6 * (spec.sigma_lateral_m + spec.spread_per_m * f_far)


@cache
def spot_texture(spec: BeamSpec) -> np.ndarray:
    """The spot's irradiance (full-scale units) on a ground grid: rows run forward from the
    lamp (0 .. reach), columns across it (-half width .. +half width), texel centres on the grid."""
    f_far, half_w = spot_extent_m(spec)
    f = (np.arange(SPOT_TEXELS_FORWARD) + 0.5) * (f_far / SPOT_TEXELS_FORWARD)
    lat = (np.arange(SPOT_TEXELS_LATERAL) + 0.5) * (2.0 * half_w / SPOT_TEXELS_LATERAL) - half_w
    width = spec.sigma_lateral_m + spec.spread_per_m * f
    e = np.exp(-(((f - spec.centre_m) / spec.sigma_forward_m) ** 2))[:, None] * np.exp(
        -((lat[None, :] / width[:, None]) ** 2)
    )
    e *= np.clip(f / 0.5, 0.0, 1.0)[:, None]  # the light starts at the lamp, not before it
    return (spec.peak_irradiance * e).astype(np.float32)


#: Spots are accumulated on a grid this many times coarser than the canvas (they are smooth).
SPOT_GRID = 4


def _spots_to_canvas(
    scene: StaticScene, agents: list[AgentState]
) -> list[tuple[BeamSpec, np.ndarray, tuple] | None]:
    """Per lit agent: (its beam, texel -> canvas homography, canvas box (x0, y0, x1, y1)), or
    None when its spot is out of view. Vectorised over the agents."""
    canvas = scene.canvas
    cam = canvas.camera
    specs = [BEAMS[a.cls] for a in agents]
    n = len(agents)
    # per agent: x, y, heading, length, width, mean lamp (forward, left) fractions, reach, half width
    rows = np.array(
        [
            (
                a.x_m,
                a.y_m,
                a.heading_rad,
                a.length_m,
                a.width_m,
                *_mean_lamp(spec),
                *spot_extent_m(spec),
            )
            for a, spec in zip(agents, specs, strict=True)
        ]
    )
    x, y, heading, length, width, f_frac, l_frac, f_far, half_w = rows.T
    c, s = np.cos(heading), np.sin(heading)
    fl, ll = f_frac * length, l_frac * width
    ox, oy = x + c * fl - s * ll, y + s * fl + c * ll  # the lamps' mean position: the beam origin
    # texel (col, row) -> ground (x, y, 1): columns run to the left of the heading, rows forward
    df, dl = f_far / SPOT_TEXELS_FORWARD, 2.0 * half_w / SPOT_TEXELS_LATERAL
    tex_to_ground = np.zeros((n, 3, 3))
    tex_to_ground[:, 0, 0], tex_to_ground[:, 0, 1] = -dl * s, df * c
    tex_to_ground[:, 0, 2] = ox + half_w * s + 0.5 * (df * c - dl * s)
    tex_to_ground[:, 1, 0], tex_to_ground[:, 1, 1] = dl * c, df * s
    tex_to_ground[:, 1, 2] = oy - half_w * c + 0.5 * (df * s + dl * c)
    tex_to_ground[:, 2, 2] = 1.0
    box_world = np.einsum("nij,kj->nki", tex_to_ground, _SPOT_BOX_TEX)  # (n, 4, 3)
    box_world[..., 2] = 0.0
    box_cam = cam.world_to_cam(box_world.reshape(-1, 3)).reshape(n, 4, 3)
    # the spot's ground box is cut where it leaves the camera's view of the ground (behind or under it)
    z_cut = 0.8 * scene.nearest_ground_cam_z_m
    whole = np.all(box_cam[..., 2] >= z_cut, axis=1)
    uv = canvas.cam_to_canvas(np.where(whole[:, None, None], box_cam, 1.0).reshape(-1, 3)).reshape(
        n, 4, 2
    )
    lo, hi = uv.min(axis=1), uv.max(axis=1)
    to_canvas = scene.ground_to_canvas @ tex_to_ground
    out: list[tuple[BeamSpec, np.ndarray, tuple] | None] = []
    for i in range(n):
        if whole[i]:
            roi = _clip_box(lo[i], hi[i], canvas)
        else:
            pts = clip_solid_near(box_cam[i], z_cut)
            roi = None if pts is None else roi_of(canvas.cam_to_canvas(pts), canvas)
        out.append(None if roi is None else (specs[i], to_canvas[i], roi))
    return out


@cache
def _mean_lamp(spec: BeamSpec) -> tuple[float, float]:
    lamps = np.array(spec.lamps_flz)
    return float(lamps[:, 0].mean()), float(lamps[:, 1].mean())


def _clip_box(lo: np.ndarray, hi: np.ndarray, canvas: Canvas) -> tuple[int, int, int, int] | None:
    x0, y0 = max(math.floor(lo[0]) - 1, 0), max(math.floor(lo[1]) - 1, 0)
    x1, y1 = min(math.ceil(hi[0]) + 2, canvas.width_px), min(math.ceil(hi[1]) + 2, canvas.height_px)
    return None if x1 <= x0 or y1 <= y0 else (x0, y0, x1, y1)


_SPOT_BOX_TEX = np.array(
    [
        [-0.5, -0.5, 1.0],
        [-0.5, SPOT_TEXELS_FORWARD - 0.5, 1.0],
        [SPOT_TEXELS_LATERAL - 0.5, -0.5, 1.0],
        [SPOT_TEXELS_LATERAL - 0.5, SPOT_TEXELS_FORWARD - 0.5, 1.0],
    ]
)


def add_ground_spots(
    scene: StaticScene, img: np.ndarray, agents: list[AgentState], gain: float
) -> None:
    """Add the light spots of lit ``agents`` to the visible ground of ``img`` (radiance).

    The canvas is an ideal pinhole image, so ground plane -> canvas is a
    homography: each spot's precomputed texture is warped with
    ``cv2.warpPerspective`` onto a coarse grid (spots are smooth), the grid is
    scaled up once and weighted by each pixel's ground reflectance (zero where
    the pixel does not see the ground).
    """
    if not agents:
        return
    canvas = scene.canvas
    h, w = canvas.shape
    g = SPOT_GRID
    ch, cw = (h + g - 1) // g, (w + g - 1) // g
    coarse = None
    # canvas -> coarse grid with pixel centres aligned as cv2.resize(INTER_LINEAR) expects
    to_coarse = np.array(
        [[1.0 / g, 0.0, 0.5 / g - 0.5], [0.0, 1.0 / g, 0.5 / g - 0.5], [0.0, 0.0, 1.0]]
    )
    for found in _spots_to_canvas(scene, agents):
        if found is None:
            continue
        spec, tex_to_canvas, (x0, y0, x1, y1) = found
        cx0, cy0 = int(max((x0 + 0.5) / g - 1.5, 0)), int(max((y0 + 0.5) / g - 1.5, 0))
        cx1, cy1 = (
            min(math.ceil((x1 - 0.5) / g + 1.5), cw),
            min(math.ceil((y1 - 0.5) / g + 1.5), ch),
        )
        if cx1 <= cx0 or cy1 <= cy0:
            continue
        to_roi = to_coarse @ tex_to_canvas
        to_roi[0] -= cx0 * to_roi[2]
        to_roi[1] -= cy0 * to_roi[2]
        patch = cv2.warpPerspective(
            spot_texture(spec),
            to_roi,
            (cx1 - cx0, cy1 - cy0),
            flags=cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_CONSTANT,
        )
        if coarse is None:
            coarse = np.zeros((ch, cw), np.float32)
        view = coarse[cy0:cy1, cx0:cx1]
        cv2.add(view, patch, dst=view)
    if coarse is None:
        return
    e = cv2.resize(coarse, (g * cw, g * ch), interpolation=cv2.INTER_LINEAR)[:h, :w]
    cv2.add(img, cv2.multiply(scene.ground_reflectance, e, scale=gain), dst=img)


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
) -> None:
    """Add a glare blob of core width ``sigma_px`` and peak radiance ``peak`` at the pixel nearest (u, v)."""
    sigma = min(sigma_px, MAX_BLOB_SIGMA_PX)
    stamp = _blob_stamp(max(1, round(sigma * BLOB_STEPS_PER_PX)))
    r = stamp.shape[0] // 2
    cu, cv_ = int(round(u)), int(round(v))
    x0, y0 = max(cu - r, 0), max(cv_ - r, 0)
    x1, y1 = min(cu + r + 1, canvas.width_px), min(cv_ + r + 1, canvas.height_px)
    if x1 <= x0 or y1 <= y0:
        return
    part = stamp[y0 - (cv_ - r) : y1 - (cv_ - r), x0 - (cu - r) : x1 - (cu - r)]
    view = img[y0:y1, x0:x1]
    cv2.scaleAdd(part, float(peak), view, dst=view)


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
    """Blobs for light sources at ``points_m`` (N, 3) with radiance x m^2 ``power`` (N,);
    sources hidden behind a nearer standing surface are left out."""
    if len(points_m) == 0:
        return
    cam = canvas.camera
    cam_pts = cam.world_to_cam(points_m)
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
    for i in np.flatnonzero(show):
        col, row = round(u[i]), round(v[i])
        if 0 <= col < w and 0 <= row < h and occluder_depth[row, col] < dist[i] - 0.3:
            continue
        _blob(canvas, img, u[i], v[i], sigma[i], peak[i])
        if mirrors is not None:
            _streak(
                canvas, img, u[i], mirrors[0][i], mirrors[1][i], sigma[i], WET_REFLECTION * peak[i]
            )


def agent_glare_sources(
    canvas: Canvas, agents: list[AgentState], ambient_light: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Light sources carried by lit agents: (points (N, 3), power (N,), size (N,)).

    A lamp shines at the camera as cos^2 of the angle between its heading and
    the camera; from behind, vehicles show their tail lights (a fraction).
    """
    lit = [(a, BEAMS[a.cls]) for a in agents if a.light_on and a.cls in BEAMS]
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
