"""Camera coverage of a street: where a lamp camera can see a person, zone by zone.

A ground point is *seen* when some lamp camera sees a person standing on it whole (feet and a
1.7 m head both inside the frame, through the pinhole projection; the detector drops regions
cut by the frame border) and within the detector's range (its forward ground distance along
the camera's heading at most ``range_m``). The walkable and drivable area is the street's lanes
and sidewalks, sampled on a grid of ``step_m`` in street coordinates (x read as s along the
centreline, y as d), placed in the world through ``Street.centreline`` for the cameras. For each lamp
zone the share of that area seen; along the street, the *blind stretches*: s intervals where no point across the lanes and
sidewalks is seen. A property of the scenario's geometry alone: no traffic is simulated.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from citysim.world.street import Street

#: The person a camera must see whole, m.
PERSON_HEIGHT_M = 1.7


@dataclass(frozen=True)
class Coverage:
    """Share of each zone's lanes and sidewalks seen (0..1, by lamp) and the blind x stretches (m)."""

    zone_seen: tuple[float, ...]
    blind_stretches_m: tuple[tuple[float, float], ...]

    @property
    def street_seen(self) -> float:
        return float(np.mean(self.zone_seen)) if self.zone_seen else 0.0

    def as_dict(self) -> dict:
        return {
            "zone_seen": [round(s, 4) for s in self.zone_seen],
            "street_seen": round(self.street_seen, 4),
            "blind_stretches_m": [[round(a, 1), round(b, 1)] for a, b in self.blind_stretches_m],
        }

    def describe(self) -> str:
        """One line for people: how much is seen, and where nobody looks."""
        blind = ", ".join(f"{a:.0f}-{b:.0f}" for a, b in self.blind_stretches_m) or "none"
        return (f"camera coverage: {100 * self.street_seen:.0f} % of the lanes and sidewalks in the lamp zones "
                f"(per zone {min(self.zone_seen, default=0):.0%}-{max(self.zone_seen, default=0):.0%}); "
                f"blind stretches (x, m): {blind}")  # fmt: skip


def _bands(street: Street) -> list[tuple[float, float]]:
    """The y extents (m) of every lane and sidewalk."""
    return [(b.y_center_m - b.width_m / 2, b.y_center_m + b.width_m / 2) for b in (*street.lanes, *street.sidewalks)]


def seen_grid(street: Street, xs_m: np.ndarray, ys_m: np.ndarray, range_m: float) -> np.ndarray:
    """Boolean (len(xs), len(ys)): is a person standing at street coordinates (s, d) = (x, y) seen by
    some camera (``Street.cameras``)? The grid is placed in the world through ``street.centreline``."""
    gx, gy = np.meshgrid(xs_m, ys_m, indexing="ij")
    wx, wy = street.centreline.to_xy(gx.ravel(), gy.ravel())
    ground = np.column_stack([wx, wy, np.zeros(gx.size)])
    head = ground + [0.0, 0.0, PERSON_HEIGHT_M]
    seen = np.zeros(gx.size, dtype=bool)
    for site in street.cameras:
        cam = site.camera
        forward = cam.forward_and_lateral_m(ground[:, :2])[:, 0]
        near = (forward > 0.0) & (forward <= range_m)
        if not near.any():
            continue
        inside = np.ones(int(near.sum()), dtype=bool)
        for pts in (ground[near], head[near]):
            uv = cam.project(pts, distort=False)
            inside &= (uv[:, 0] >= 0) & (uv[:, 0] <= cam.width_px - 1) & (uv[:, 1] >= 0) & (uv[:, 1] <= cam.height_px - 1)
        hit = np.flatnonzero(near)[inside]
        seen[hit] = True
    return seen.reshape(gx.shape)


@dataclass(frozen=True)
class CoverageGrid:
    """The sampled walkable and drivable area of the lamp zones: cell centres (m) and which are seen."""

    xs_m: np.ndarray
    ys_m: np.ndarray
    seen: np.ndarray  # bool (len(xs_m), len(ys_m))
    step_m: float
    end_m: float  # where the last lamp zone ends


def coverage_grid(street: Street, range_m: float = 25.0, step_m: float = 0.5) -> CoverageGrid:
    """The lanes and sidewalks of the lamp zones on a ``step_m`` grid, each cell seen or not."""
    start_m = min(s.zone_start_m for s in street.lamps)
    end_m = max(s.zone_end_m for s in street.lamps)
    xs_m = np.arange(start_m + step_m / 2, end_m, step_m)
    ys_m = np.concatenate([np.arange(lo + step_m / 2, hi, step_m) for lo, hi in _bands(street)])
    return CoverageGrid(xs_m, ys_m, seen_grid(street, xs_m, ys_m, range_m), step_m, end_m)


def camera_coverage(street: Street, range_m: float = 25.0, step_m: float = 0.5) -> Coverage:
    """The coverage of ``street``'s lamp cameras for a detector that reports up to ``range_m``."""
    grid = coverage_grid(street, range_m, step_m)
    xs_m, seen = grid.xs_m, grid.seen
    zone_seen = tuple(
        float(seen[(xs_m >= s.zone_start_m) & (xs_m < s.zone_end_m)].mean()) for s in street.lamps
    )
    return Coverage(zone_seen, blind_stretches_m(grid))


def blind_stretches_m(grid: CoverageGrid) -> tuple[tuple[float, float], ...]:
    """The x intervals (m) where no cell across the lanes and sidewalks is seen."""
    half = grid.step_m / 2
    blind_x = ~grid.seen.any(axis=1)
    stretches = []
    run_start = None
    for x, blind in zip(grid.xs_m, blind_x, strict=True):
        if blind and run_start is None:
            run_start = x - half
        elif not blind and run_start is not None:
            stretches.append((float(run_start), float(x - half)))
            run_start = None
    if run_start is not None:
        stretches.append((float(run_start), float(grid.end_m)))
    return tuple(stretches)


#: How deep the approach to an end zone must be watched for its lamp to wait for what comes, m:
#: a car at 60 km/h covers 10 m in 0.6 s, about a confirmation (6 frames at 15 fps) and a ramp.
APPROACH_WATCH_M = 10.0


def approaches_seen(street: Street, range_m: float = 25.0, step_m: float = 0.5,
                    depth_m: float = APPROACH_WATCH_M) -> tuple[float, float]:
    """Share of the lanes and sidewalks seen on the ``depth_m`` before the first lamp zone and after
    the last one (0..1 each): whoever comes from an unseen approach enters its end zone unannounced."""
    start_m = min(s.zone_start_m for s in street.lamps)
    end_m = max(s.zone_end_m for s in street.lamps)
    ys_m = np.concatenate([np.arange(lo + step_m / 2, hi, step_m) for lo, hi in _bands(street)])
    shares = []
    for lo_m, hi_m in ((start_m - depth_m, start_m), (end_m, end_m + depth_m)):
        xs_m = np.arange(lo_m + step_m / 2, hi_m, step_m)
        shares.append(float(seen_grid(street, xs_m, ys_m, range_m).mean()) if len(xs_m) else 0.0)
    return shares[0], shares[1]
