"""Headlight and flashlight spots on the ground ahead of lit agents.

A lit agent (``AgentState.light_on``, a kind with a beam: ``citysim.render.beams.beam_of``)
throws a spot on the ground ahead of it:
``E = peak * exp(-((f - centre)/sigma_f)^2) * exp(-(l / (sigma_l + spread * f))^2)``
for ground points ``f`` m ahead of and ``l`` m beside its lamps' mean
position, zero behind it (fading in over the first 0.5 m) and outside a
ground box that holds the spot (``spot_extent_m``). Only pixels that see the
ground get it (the spot lands before the agents are drawn, so they hide it).

Spots are smooth, so ``E`` is evaluated at the centres of a grid SPOT_GRID
times coarser than the canvas (``citysim.render.kernels.add_spots``, all lit agents in
one call, each only over the cells its ground box covers), scaled up only
where it lights the ground visibly and weighted by each pixel's ground
reflectance.

Conventions: canvas pixels (``citysim.render.canvas``), world frame of
docs/design/architecture.md (m), radiance in linear full-scale units.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from functools import cache

import cv2
import numpy as np

from citysim.render.background import StaticScene
from citysim.render.beams import BeamSpec, beam_of
from citysim.render.kernels import add_spots as add_spot_cells
from citysim.world.agents import AgentState

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


@dataclass(frozen=True, eq=False)
class SpotClass:
    """One class's spot, ready to draw: where it lies relative to the agent and its beam."""

    #: (forward, left) of the lamps' mean position as fractions of length and width, the
    #: forward reach (m) and half width (m) of the ground box holding the spot
    layout: tuple[float, float, float, float]
    #: layout, then the beam's peak irradiance, centre (m), forward and lateral sigma (m) and
    #: spread per metre: what ``citysim.render.kernels.add_spots`` takes per spot
    row: tuple[float, ...]


@cache
def spot_class(cls: str) -> SpotClass:
    """The spot of kind ``cls``'s beam."""
    spec = beam_of(cls)
    if spec is None:
        raise ValueError(f"agent class {cls!r} carries no beam")
    lamps = np.array(spec.lamps_flz)
    f_far, half_w = spot_extent_m(spec)
    layout = (float(lamps[:, 0].mean()), float(lamps[:, 1].mean()), f_far, half_w)
    beam = (
        spec.peak_irradiance,
        spec.centre_m,
        spec.sigma_forward_m,
        spec.sigma_lateral_m,
        spec.spread_per_m,
    )
    return SpotClass(layout, layout + beam)


def spot_reach(agents: list[AgentState]) -> tuple[np.ndarray, np.ndarray]:
    """Ground centre (N, 3) and radius (N,) m of a sphere holding each lit agent's spot."""
    rows = np.array(
        [(a.x_m, a.y_m, a.heading_rad, a.length_m, *spot_class(a.cls).layout[2:]) for a in agents]
    )
    x, y, heading, length, f_far, half_w = rows.T
    mid = 0.5 * (length + f_far)
    centre = np.column_stack([x + mid * np.cos(heading), y + mid * np.sin(heading), 0.0 * x])
    return centre, np.hypot(0.5 * f_far + length, half_w)


class SpotGrid:
    """One camera's coarse grid for spots: the ground point each cell centre sees."""

    def __init__(self, scene: StaticScene) -> None:
        canvas = scene.canvas
        h, w = canvas.shape
        g = SPOT_GRID
        self.shape = ((h + g - 1) // g, (w + g - 1) // g)
        # canvas (u, v) = g * (cell + 1/2) - 1/2 on the pinhole canvas
        to_canvas = np.array([[g, 0.0, 0.5 * g - 0.5], [0.0, g, 0.5 * g - 0.5], [0.0, 0.0, 1.0]])
        self.ground_to_cell = np.linalg.inv(to_canvas) @ scene.ground_to_canvas
        rows, cols = np.mgrid[0 : self.shape[0], 0 : self.shape[1]]
        cells = np.stack([cols, rows, np.ones_like(rows)], axis=-1).reshape(-1, 3).astype(float)
        ground = cells @ np.linalg.inv(self.ground_to_cell).T
        # a cell sees the ground where its ray points down: the homography's scale is positive
        cam = canvas.camera
        ray_cam = (to_canvas @ cells.T).T
        ray_cam[:, 0] = (ray_cam[:, 0] + canvas.x0_px - cam.cx_px) / cam.fx_px
        ray_cam[:, 1] = (ray_cam[:, 1] + canvas.y0_px - cam.cy_px) / cam.fy_px
        ray_cam[:, 2] = 1.0
        down = (ray_cam @ cam.rotation_world_to_cam)[:, 2] < -1e-9
        xy = np.full((len(cells), 2), np.nan)
        xy[down] = ground[down, :2] / ground[down, 2:]
        self.cell_ground_m = xy.reshape(*self.shape, 2)


_GRIDS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def spot_grid(scene: StaticScene) -> SpotGrid:
    grid = _GRIDS.get(scene)
    if grid is None:
        grid = _GRIDS[scene] = SpotGrid(scene)
    return grid


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
    grid = spot_grid(scene)
    rows = np.array(
        [
            (a.x_m, a.y_m, a.heading_rad, a.length_m, a.width_m, *spot_class(a.cls).row)
            for a in agents
        ]
    )
    x, y, heading, length, width, f_frac, l_frac = rows[:, :7].T
    c, s = np.cos(heading), np.sin(heading)
    fl, ll = f_frac * length, l_frac * width
    spots = np.column_stack([x + c * fl - s * ll, y + s * fl + c * ll, c, s, rows[:, 7:]])
    coarse = np.zeros(grid.shape, np.float32)
    touched = np.empty(4, np.int64)
    add_spot_cells(coarse, grid.cell_ground_m, grid.ground_to_cell, spots, touched)
    ux0, uy0, ux1, uy1 = touched.tolist()
    if ux1 <= ux0:
        return []
    ch, cw = grid.shape  # a cell of margin for the dilation below
    ux0, uy0, ux1, uy1 = max(ux0 - 1, 0), max(uy0 - 1, 0), min(ux1 + 1, cw), min(uy1 + 1, ch)
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
