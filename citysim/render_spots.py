"""Headlight and flashlight spots on the ground ahead of lit agents.

A lit agent (``AgentState.light_on``, a class in ``render_beams.BEAMS``)
throws a spot on the ground ahead of it:
``E = peak * exp(-((f - centre)/sigma_f)^2) * exp(-(l / (sigma_l + spread * f))^2)``
for ground points ``f`` m ahead of and ``l`` m beside its lamps' mean
position, zero behind it. Only pixels that see the ground get it (the spot
lands before the agents are drawn, so they hide it).

The canvas is an ideal pinhole image, so ground plane -> canvas is a
homography: each class's spot is a precomputed texture, warped with
``cv2.warpPerspective`` onto a grid SPOT_GRID times coarser than the canvas
(spots are smooth), summed, scaled up only where they light the ground visibly and
weighted by each pixel's ground reflectance. Everything but the warps is
done for all lit agents at once.

Conventions: canvas pixels (``citysim.render_canvas``), world frame of
DESIGN.md (m), radiance in linear full-scale units.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import cv2
import numpy as np

from citysim.agents import AgentState
from citysim.render_background import StaticScene
from citysim.render_beams import BEAMS, BeamSpec
from citysim.render_canvas import clip_solid_near, roi_of

SPOT_TEXELS_FORWARD, SPOT_TEXELS_LATERAL = 96, 48
#: Spots are accumulated on a grid this many times coarser than the canvas (they are smooth).
SPOT_GRID = 4
#: Irradiance (full-scale units) below which a spot adds nothing visible (under 1 DN on a
#: dark road); the canvas is only touched where a spot exceeds it
SPOT_MIN_IRRADIANCE = 0.002
_CELL_MARGIN = np.ones((3, 3), np.uint8)


def spot_extent_m(spec: BeamSpec) -> tuple[float, float]:
    """(forward reach, half width) of the ground box that holds the spot, m."""
    f_far = spec.centre_m + 2.0 * spec.sigma_forward_m
    return f_far, 1.6 * (spec.sigma_lateral_m + spec.spread_per_m * f_far)


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


@dataclass(frozen=True, eq=False)
class SpotClass:
    """One class's spot, ready to draw: texture and where it lies relative to the agent."""

    texture: np.ndarray
    #: (forward, left) of the lamps' mean position as fractions of length and width, the
    #: forward reach (m) and half width (m) of the ground box holding the spot
    layout: tuple[float, float, float, float]


@cache
def spot_class(cls: str) -> SpotClass:
    spec = BEAMS[cls]
    lamps = np.array(spec.lamps_flz)
    f_far, half_w = spot_extent_m(spec)
    texture = spot_texture(spec)
    texture.flags.writeable = False
    return SpotClass(texture, (float(lamps[:, 0].mean()), float(lamps[:, 1].mean()), f_far, half_w))


def spot_reach(agents: list[AgentState]) -> tuple[np.ndarray, np.ndarray]:
    """Ground centre (N, 3) and radius (N,) m of a sphere holding each lit agent's spot."""
    rows = np.array(
        [(a.x_m, a.y_m, a.heading_rad, a.length_m, *spot_class(a.cls).layout[2:]) for a in agents]
    )
    x, y, heading, length, f_far, half_w = rows.T
    mid = 0.5 * (length + f_far)
    centre = np.column_stack([x + mid * np.cos(heading), y + mid * np.sin(heading), 0.0 * x])
    return centre, np.hypot(0.5 * f_far + length, half_w)


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
) -> list[tuple[int, int, int, int]]:
    """Add the light spots of lit ``agents`` to the visible ground of ``img`` (radiance);
    returns the canvas boxes drawn on (see the module docstring)."""
    if not agents:
        return []
    canvas = scene.canvas
    h, w = canvas.shape
    g = SPOT_GRID
    ch, cw = (h + g - 1) // g, (w + g - 1) // g
    classes = [spot_class(a.cls) for a in agents]
    rows = np.array(
        [
            (a.x_m, a.y_m, a.heading_rad, a.length_m, a.width_m, *k.layout)
            for a, k in zip(agents, classes, strict=True)
        ]
    )
    n = len(agents)
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
    box_cam = canvas.camera.world_to_cam(box_world.reshape(-1, 3)).reshape(n, 4, 3)
    # the spot's ground box is cut where it leaves the camera's view of the ground (behind or under it)
    z_cut = 0.8 * scene.nearest_ground_cam_z_m
    whole = np.all(box_cam[..., 2] >= z_cut, axis=1)
    uv = canvas.cam_to_canvas(np.where(whole[:, None, None], box_cam, 1.0).reshape(-1, 3))
    uv = uv.reshape(n, 4, 2)
    roi = np.concatenate(
        [np.floor(uv.min(axis=1)) - 1.0, np.ceil(uv.max(axis=1)) + 2.0], axis=1
    )  # canvas boxes (x0, y0, x1, y1)
    roi = np.minimum(np.maximum(roi, 0.0), [w, h, w, h])
    for i in np.flatnonzero(~whole).tolist():
        pts = clip_solid_near(box_cam[i], z_cut)
        cut = None if pts is None else roi_of(canvas.cam_to_canvas(pts), canvas)
        roi[i] = cut if cut is not None else (0, 0, 0, 0)
    # canvas box -> coarse cells, with a cell and a half of margin for the interpolation
    cells = np.concatenate(
        [
            np.floor(np.maximum((roi[:, :2] + 0.5) / g - 1.5, 0.0)),
            np.minimum(np.ceil((roi[:, 2:] - 0.5) / g + 1.5), [cw, ch]),
        ],
        axis=1,
    ).astype(np.int64)
    cells[(roi[:, 2] <= roi[:, 0]) | (roi[:, 3] <= roi[:, 1])] = 0
    to_coarse = np.array(
        [[1.0 / g, 0.0, 0.5 / g - 0.5], [0.0, 1.0 / g, 0.5 / g - 0.5], [0.0, 0.0, 1.0]]
    )
    to_cells = to_coarse @ scene.ground_to_canvas @ tex_to_ground  # (n, 3, 3)
    # each warp writes its cells' box from (0, 0): move the cell origin there
    to_cells[:, 0] -= cells[:, :1] * to_cells[:, 2]
    to_cells[:, 1] -= cells[:, 1:2] * to_cells[:, 2]
    coarse = None
    for i, (cx0, cy0, cx1, cy1) in enumerate(cells.tolist()):
        if cx1 <= cx0 or cy1 <= cy0:
            continue
        patch = cv2.warpPerspective(
            classes[i].texture,
            to_cells[i],
            (cx1 - cx0, cy1 - cy0),
            flags=cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_CONSTANT,
        )
        if coarse is None:
            coarse = np.zeros((ch, cw), np.float32)
            ux0, uy0, ux1, uy1 = cx0, cy0, cx1, cy1
        else:
            ux0, uy0, ux1, uy1 = min(ux0, cx0), min(uy0, cy0), max(ux1, cx1), max(uy1, cy1)
        view = coarse[cy0:cy1, cx0:cx1]
        cv2.add(view, patch, dst=view)
    if coarse is None:
        return []
    # scale up only the cells the spots light, in boxes around each lit patch with a cell of
    # margin: the interpolation then meets the same neighbours as in a scaling of the whole grid
    lit = cv2.compare(coarse[uy0:uy1, ux0:ux1], SPOT_MIN_IRRADIANCE / gain, cv2.CMP_GT)
    lit = cv2.dilate(lit, _CELL_MARGIN)
    count, _, stats, _ = cv2.connectedComponentsWithStats(lit, connectivity=8)
    cells_lit = [
        (ux0 + bx, uy0 + by, ux0 + bx + bw, uy0 + by + bh)
        for bx, by, bw, bh in stats[1:count, :4].tolist()
    ]
    boxes = []
    for ex0, ey0, ex1, ey1 in _disjoint(cells_lit):
        x0, y0 = g * ex0, g * ey0
        x1, y1 = min(g * ex1, w), min(g * ey1, h)
        e = cv2.resize(
            coarse[ey0:ey1, ex0:ex1],
            (g * (ex1 - ex0), g * (ey1 - ey0)),
            interpolation=cv2.INTER_LINEAR,
        )
        if gain != 1.0:
            e *= gain
        view = img[y0:y1, x0:x1]
        cv2.accumulateProduct(scene.ground_reflectance[y0:y1, x0:x1], e[: y1 - y0, : x1 - x0], view)
        boxes.append((x0, y0, x1, y1))
    return boxes


def _disjoint(boxes: list[tuple[int, int, int, int]]) -> list[tuple[int, int, int, int]]:
    """Boxes joined until none overlap (light must be added once)."""
    out = list(boxes)
    merged = True
    while merged:
        merged = False
        for i in range(len(out)):
            for j in range(i + 1, len(out)):
                a, b = out[i], out[j]
                if a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]:
                    out[i] = (min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), max(a[3], b[3]))
                    del out[j]
                    merged = True
                    break
            if merged:
                break
    return out
