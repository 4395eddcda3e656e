"""Where each street of a city lies on the city map: its centreline and lamps in one common frame.

Convention: local east/north metres (x east, y north). A street's centreline is its
``street.centreline_m`` polyline when the scenario has one, else the straight ``[[0, 0],
[length_m, 0]]``; a lamp at street coordinates (s along the centreline, d to its left) sits at
``a + t (s - s_a) + n d`` on the segment from ``a`` holding s (t its unit direction, n = t turned
90 deg counter-clockwise). When every street has ``street.origin`` (latitude and longitude of its
local (0, 0)), each local frame is shifted to the first street's origin by an equirectangular
projection (east = R cos(lat0) dlon, north = R dlat; metres-exact over a city); otherwise the
streets are laid out as they are, in rows of a grid, ``GRID_GAP_M`` apart, each labelled.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from citysim.config.scenario import Scenario

EARTH_RADIUS_M = 6_371_008.8
#: Space between two streets of the grid layout, m.
GRID_GAP_M = 40.0


def centreline_m(scenario: Scenario) -> list[tuple[float, float]]:
    """The street's centreline in its local frame (east, north metres)."""
    given = getattr(scenario.street, "centreline_m", None)
    if given:
        return [(float(x), float(y)) for x, y in given]
    return [(0.0, 0.0), (float(scenario.street.length_m), 0.0)]


def lamp_sd_m(scenario: Scenario) -> list[tuple[float, float]]:
    """Each lamp's (s, d) in street coordinates: surveyed poles when given, else x_m read as s and y_m as d."""
    poles = getattr(scenario.lamps, "poles", None)
    if poles:
        return [(float(p.s_m), float(p.d_m)) for p in poles]
    return [(float(x), float(scenario.lamps.y_m)) for x in scenario.lamps.positions_x_m]


def place(line: Sequence[tuple[float, float]], s_m: float, d_m: float) -> tuple[float, float]:
    """The point at (s, d) of the polyline ``line`` (s clamped to its ends), local metres."""
    segments = list(zip(line[:-1], line[1:], strict=True))
    along = 0.0
    for i, ((ax, ay), (bx, by)) in enumerate(segments):
        seg = math.hypot(bx - ax, by - ay)
        if s_m <= along + seg or i == len(segments) - 1:
            tx, ty = (bx - ax) / seg, (by - ay) / seg
            u = min(max(s_m - along, 0.0), seg)
            return ax + tx * u - ty * d_m, ay + ty * u + tx * d_m
        along += seg
    raise ValueError("a centreline needs at least two points")


def origin_of(scenario: Scenario) -> tuple[float, float] | None:
    origin = getattr(scenario.street, "origin", None)
    return None if origin is None else (float(origin.latitude_deg), float(origin.longitude_deg))


def offset_m(origin: tuple[float, float], reference: tuple[float, float]) -> tuple[float, float]:
    """East and north metres of ``origin`` (lat, lon deg) from ``reference`` (equirectangular)."""
    lat0 = math.radians(reference[0])
    return (EARTH_RADIUS_M * math.cos(lat0) * math.radians(origin[1] - reference[1]),
            EARTH_RADIUS_M * math.radians(origin[0] - reference[0]))  # fmt: skip


def city_layout(scenarios: Sequence[Scenario]) -> tuple[str, list[dict]]:
    """("origin" | "grid", per street {"centreline_m": [[x, y], ...], "lamps_m": [[x, y], ...]}) in one frame."""
    local = []
    for sc in scenarios:
        line = centreline_m(sc)
        local.append((line, [place(line, s, d) for s, d in lamp_sd_m(sc)]))
    origins = [origin_of(sc) for sc in scenarios]
    if scenarios and all(o is not None for o in origins):
        shifts = [offset_m(o, origins[0]) for o in origins]
        mode = "origin"
    else:
        shifts = grid_shifts([line + lamps for line, lamps in local])
        mode = "grid"
    out = []
    for (line, lamps), (dx, dy) in zip(local, shifts, strict=True):
        out.append({"centreline_m": [[round(x + dx, 3), round(y + dy, 3)] for x, y in line],
                    "lamps_m": [[round(x + dx, 3), round(y + dy, 3)] for x, y in lamps]})  # fmt: skip
    return mode, out


def grid_shifts(points: Sequence[Sequence[tuple[float, float]]]) -> list[tuple[float, float]]:
    """Shifts that lay the streets out in rows (about square overall), each bounding box GRID_GAP_M apart."""
    columns = max(1, math.ceil(math.sqrt(len(points))))
    boxes = [(min(x for x, _ in p), min(y for _, y in p), max(x for x, _ in p), max(y for _, y in p)) for p in points]
    width = max(b[2] - b[0] for b in boxes) + GRID_GAP_M
    height = max(b[3] - b[1] for b in boxes) + GRID_GAP_M
    return [(i % columns * width - b[0], -(i // columns) * height - b[1]) for i, b in enumerate(boxes)]
