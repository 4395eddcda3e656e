"""The street's static solids and ground paint, as the renderer's ray caster sees them.

``Street.scenery`` holds labelled boxes; here each kind becomes simple solids
(axis-aligned boxes and ellipsoids) through a registry, luminaire heads (and
lamp poles the scenery lacks) are added, and the ground's near-infrared
reflectance is painted by band (lane, kerb, sidewalk, verge, lane markings,
zebra crossings) with a fixed world-space grain.

Conventions: world frame of docs/design/architecture.md (x along the street, y across, z up,
m); boxes are axis-aligned (a ``StaticObject``'s length runs along x).
Ray casts take a ray origin (3,) and unit directions (N, 3) and return the
distance ``t_m`` along the ray (inf on a miss) and the unit surface normal.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from citysim.world.street import StaticObject, Street

KERB_WIDTH_M = 0.15
KERB_IR_REFLECTANCE = 0.45
MARKING_WIDTH_M = 0.12
#: Road paint carries glass beads: retroreflective, so bright under the emitter.
MARKING_IR_REFLECTANCE = 0.65
DASH_ON_M, DASH_OFF_M = 3.0, 6.0
ZEBRA_LENGTH_M, ZEBRA_BAR_M = 3.0, 0.5
GRAIN_CELL_M = 0.12
GRAIN_AMPLITUDE = 0.08
POLE_WIDTH_M = 0.16
TRUNK_WIDTH_M = 0.28


@dataclass(frozen=True, eq=False)
class Box:
    lo_m: np.ndarray  # (3,) min corner
    hi_m: np.ndarray  # (3,) max corner
    ir_reflectance: float

    def corners_m(self) -> np.ndarray:
        lo, hi = self.lo_m, self.hi_m
        return np.array(
            [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
        )

    def contains_xy(self, x_m: float, y_m: float, margin_m: float = 0.0) -> bool:
        return bool(
            self.lo_m[0] - margin_m <= x_m <= self.hi_m[0] + margin_m
            and self.lo_m[1] - margin_m <= y_m <= self.hi_m[1] + margin_m
        )

    def cast(self, origin_m: np.ndarray, dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Slab test; rays starting inside the box miss (the camera looks out of it)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            safe = np.where(np.abs(dirs) < 1e-12, 1e-12, dirs)
            inv = 1.0 / safe
            t1 = (self.lo_m - origin_m) * inv
            t2 = (self.hi_m - origin_m) * inv
        tmin, tmax = np.minimum(t1, t2), np.maximum(t1, t2)
        t_near, t_far = tmin.max(axis=1), tmax.min(axis=1)
        hit = (t_near <= t_far) & (t_near > 1e-6)
        axis = tmin.argmax(axis=1)
        normal = np.zeros_like(dirs)
        rows = np.arange(len(dirs))
        normal[rows, axis] = -np.sign(dirs[rows, axis])
        return np.where(hit, t_near, np.inf), normal


@dataclass(frozen=True, eq=False)
class Ellipsoid:
    centre_m: np.ndarray  # (3,)
    radii_m: np.ndarray  # (3,) semi-axes along x, y, z
    ir_reflectance: float

    def corners_m(self) -> np.ndarray:
        lo, hi = self.centre_m - self.radii_m, self.centre_m + self.radii_m
        return Box(lo, hi, 0.0).corners_m()

    def contains_xy(self, x_m: float, y_m: float, margin_m: float = 0.0) -> bool:
        d = (np.array([x_m, y_m]) - self.centre_m[:2]) / (self.radii_m[:2] + margin_m)
        return bool(d @ d <= 1.0)

    def cast(self, origin_m: np.ndarray, dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        o = (origin_m - self.centre_m) / self.radii_m
        d = dirs / self.radii_m
        a = np.einsum("nk,nk->n", d, d)
        b = 2.0 * (d @ o)
        c = o @ o - 1.0
        disc = b * b - 4.0 * a * c
        with np.errstate(invalid="ignore"):
            t = (-b - np.sqrt(disc)) / (2.0 * a)
        hit = (disc >= 0.0) & (t > 1e-6)
        t = np.where(hit, t, np.inf)
        p = o + np.where(hit, t, 0.0)[:, None] * d
        normal = p / self.radii_m
        normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
        return t, normal


Solid = Box | Ellipsoid


@dataclass(frozen=True)
class SceneryParts:
    """Solids of the static scene; tree crowns kept apart because they sway."""

    solids: tuple[Solid, ...]
    crowns: tuple[Ellipsoid, ...]


def _box_from(
    obj: StaticObject, z0_m: float = 0.0, z1_m: float | None = None, scale_xy: float = 1.0
) -> Box:
    hl, hw = obj.length_m / 2 * scale_xy, obj.width_m / 2 * scale_xy
    top = obj.height_m if z1_m is None else z1_m
    return Box(
        np.array([obj.x_m - hl, obj.y_m - hw, z0_m]),
        np.array([obj.x_m + hl, obj.y_m + hw, top]),
        obj.ir_reflectance,
    )


def _plain(obj: StaticObject) -> tuple[list[Solid], list[Ellipsoid]]:
    return [_box_from(obj)], []


def _parked_car(obj: StaticObject) -> tuple[list[Solid], list[Ellipsoid]]:
    """Body on wheels plus a narrower, shorter cabin (the car runs along x)."""
    h = obj.height_m
    body = _box_from(obj, 0.18, 0.58 * h)
    cabin_len, cabin_w = 0.55 * obj.length_m, 0.88 * obj.width_m
    cabin = Box(
        np.array([obj.x_m - 0.6 * cabin_len, obj.y_m - cabin_w / 2, 0.58 * h]),
        np.array([obj.x_m + 0.4 * cabin_len, obj.y_m + cabin_w / 2, h]),
        0.5 * obj.ir_reflectance,  # glass returns little of the emitter's light
    )
    wheels = []
    for fx in (-0.33, 0.33):
        for side in (-1.0, 1.0):
            cx, cy = obj.x_m + fx * obj.length_m, obj.y_m + side * (obj.width_m / 2 - 0.12)
            wheels.append(
                Box(np.array([cx - 0.3, cy - 0.1, 0.0]), np.array([cx + 0.3, cy + 0.1, 0.6]), 0.1)
            )
    return [body, cabin, *wheels], []


def _tree(obj: StaticObject) -> tuple[list[Solid], list[Ellipsoid]]:
    """A trunk under an ellipsoidal crown filling the object's box above 35 % of its height."""
    h = obj.height_m
    trunk = Box(
        np.array([obj.x_m - TRUNK_WIDTH_M / 2, obj.y_m - TRUNK_WIDTH_M / 2, 0.0]),
        np.array([obj.x_m + TRUNK_WIDTH_M / 2, obj.y_m + TRUNK_WIDTH_M / 2, 0.5 * h]),
        0.3,
    )
    crown = Ellipsoid(
        np.array([obj.x_m, obj.y_m, 0.675 * h]),
        np.array([obj.length_m / 2, obj.width_m / 2, 0.325 * h]),
        obj.ir_reflectance,
    )
    return [trunk], [crown]


#: How each ``StaticObject.kind`` is built from solids.
SCENERY_KINDS: dict[str, Callable[[StaticObject], tuple[list[Solid], list[Ellipsoid]]]] = {
    "wall": _plain,
    "building": _plain,
    "hedge": _plain,
    "pole": _plain,
    "parked_car": _parked_car,
    "tree": _tree,
}


def scenery_parts(street: Street, camera_xy_m: tuple[float, float]) -> SceneryParts:
    """All static solids of ``street`` plus its lamp poles, minus anything the camera stands in.

    Raises ValueError naming the object and the valid kinds for an unknown kind.
    """
    solids: list[Solid] = []
    crowns: list[Ellipsoid] = []
    for i, obj in enumerate(street.scenery):
        build = SCENERY_KINDS.get(obj.kind)
        if build is None:
            raise ValueError(
                f"street.scenery[{i}].kind: unknown kind {obj.kind!r}; valid kinds: {sorted(SCENERY_KINDS)}"
            )
        s, c = build(obj)
        solids += s
        crowns += c
    for lamp in street.lamps:
        half = POLE_WIDTH_M / 2
        has_pole = any(
            o.kind == "pole" and abs(o.x_m - lamp.x_m) < 0.3 and abs(o.y_m - lamp.y_m) < 0.3
            for o in street.scenery
        )
        if not has_pole:  # streets built by hand may leave the lamp poles out of the scenery
            solids.append(
                Box(
                    np.array([lamp.x_m - half, lamp.y_m - half, 0.0]),
                    np.array([lamp.x_m + half, lamp.y_m + half, lamp.pole_height_m]),
                    0.3,
                )
            )
        solids.append(  # the luminaire housing
            Box(
                np.array([lamp.x_m - 0.35, lamp.y_m - 0.15, lamp.pole_height_m]),
                np.array([lamp.x_m + 0.35, lamp.y_m + 0.15, lamp.pole_height_m + 0.15]),
                0.4,
            )
        )
    # the camera's own pole (and a crown it hangs in) would fill the frame edge-on: leave them out
    cx, cy = camera_xy_m
    solids = [s for s in solids if not s.contains_xy(cx, cy, margin_m=0.05)]
    crowns = [c for c in crowns if not c.contains_xy(cx, cy, margin_m=0.05)]
    return SceneryParts(tuple(solids), tuple(crowns))


def _grain(x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
    """Deterministic world-space texture in [-1, 1] on GRAIN_CELL_M cells (same for every camera)."""
    ix = np.floor(x_m / GRAIN_CELL_M)
    iy = np.floor(y_m / GRAIN_CELL_M)
    h = np.sin(ix * 12.9898 + iy * 78.233) * 43758.5453
    return 2.0 * (h - np.floor(h)) - 1.0


def ground_reflectance(street: Street, x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
    """Near-infrared reflectance of the ground at world points (x, y), any shape.

    The street's strips are looked up in street coordinates (s, d) through ``street.centreline``;
    the grain is a texture on the world ground."""
    grain = _grain(x_m, y_m)
    line = getattr(street, "centreline", None)
    if line is not None and not line.is_straight_x:
        x_m, y_m = line.to_sd(x_m, y_m)  # from here on x_m is s and y_m is d
    rho = np.full(np.shape(x_m), street.verge_ir_reflectance, dtype=np.float64)
    for sw in street.sidewalks:
        rho[np.abs(y_m - sw.y_center_m) <= sw.width_m / 2] = street.sidewalk_ir_reflectance
    if street.lanes:
        lanes = sorted(street.lanes, key=lambda lane: lane.y_center_m)
        for lane in lanes:
            rho[np.abs(y_m - lane.y_center_m) <= lane.width_m / 2] = street.road_ir_reflectance
        road_lo = lanes[0].y_center_m - lanes[0].width_m / 2
        road_hi = lanes[-1].y_center_m + lanes[-1].width_m / 2
        rho[(y_m < road_lo) & (y_m >= road_lo - KERB_WIDTH_M)] = KERB_IR_REFLECTANCE
        rho[(y_m > road_hi) & (y_m <= road_hi + KERB_WIDTH_M)] = KERB_IR_REFLECTANCE
        for a, b in zip(lanes[:-1], lanes[1:], strict=True):
            y_line = (a.y_center_m + a.width_m / 2 + b.y_center_m - b.width_m / 2) / 2
            on_line = np.abs(y_m - y_line) <= MARKING_WIDTH_M / 2
            if a.direction == b.direction:  # dashed between lanes of one direction
                on_line &= np.mod(x_m, DASH_ON_M + DASH_OFF_M) < DASH_ON_M
            rho[on_line] = MARKING_IR_REFLECTANCE
        on_road = (y_m >= road_lo) & (y_m <= road_hi)
        for x_c in getattr(street, "crossings_x_m", ()):
            # zebra: bars along the traffic, ZEBRA_BAR_M wide with equal gaps, across the road
            bars = on_road & (np.abs(x_m - x_c) <= ZEBRA_LENGTH_M / 2)
            bars &= np.mod(y_m - road_lo, 2.0 * ZEBRA_BAR_M) < ZEBRA_BAR_M
            rho[bars] = MARKING_IR_REFLECTANCE
    return rho * (1.0 + GRAIN_AMPLITUDE * grain)
