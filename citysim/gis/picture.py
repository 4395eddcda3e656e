"""The top-down picture of an imported street, drawn from its scenario data (not from a world).

Grey: other ways nearby (OSM geometry); black: the centreline, with the lanes and sidewalks as
outlines; coloured bands: each lamp's zone (the stretch of street nearest to it in s); pale
polygons: each camera's ground footprint out to VIEW_RANGE_M; red: blind stretches of the
centreline no camera sees within that range; triangles: side entries. Local east/north metres.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from citysim.gis.geometry import cumulative_s, offset_point, point_at

#: How far along the ground a camera's view is drawn: the distance a lamp camera sees people at, m.
VIEW_RANGE_M = 25.0
#: The picture shows this much around the street, m.
ZOOM_MARGIN_M = 35.0
#: Step along the centreline for outlines and blind stretches, m.
STEP_M = 0.5


def zone_bounds_m(poles_s_m: list[float], length_m: float) -> list[tuple[float, float]]:
    """Each lamp's zone as an s interval (m): cut half-way between neighbouring lamps; the first
    and last zones reach half their neighbour gap beyond their lamp (within the street)."""
    s = list(poles_s_m)
    if len(s) == 1:
        return [(0.0, length_m)]
    cuts = [(a + b) / 2 for a, b in zip(s, s[1:], strict=False)]
    first = max(0.0, s[0] - (s[1] - s[0]) / 2)
    last = min(length_m, s[-1] + (s[-1] - s[-2]) / 2)
    edges = [first, *cuts, last]
    return list(zip(edges, edges[1:], strict=False))


def footprint_m(x_m: float, y_m: float, height_m: float, heading_deg: float, camera: dict) -> np.ndarray:
    """A camera's ground footprint as a polygon of (x_m, y_m): the image border's rays met with the
    ground, each cut at VIEW_RANGE_M horizontally. ``heading_deg`` is the world yaw (CCW from +x);
    camera['tilt_deg'] the depression below the horizon; focal_mm and sensor_*_mm the optics."""
    psi, tau = math.radians(heading_deg), math.radians(camera["tilt_deg"])
    fwd = np.array([math.cos(psi) * math.cos(tau), math.sin(psi) * math.cos(tau), -math.sin(tau)])
    right = np.array([math.sin(psi), -math.cos(psi), 0.0])
    down = np.array([-math.cos(psi) * math.sin(tau), -math.sin(psi) * math.sin(tau), -math.cos(tau)])
    half_w, half_h = camera["sensor_w_mm"] / 2 / camera["focal_mm"], camera["sensor_h_mm"] / 2 / camera["focal_mm"]
    t = np.linspace(-1, 1, 21)
    border = [(a, -half_h) for a in t * half_w] + [(half_w, b) for b in t * half_h] + \
             [(a, half_h) for a in -t * half_w] + [(-half_w, b) for b in -t * half_h]
    pts = []
    for a, b in border:
        ray = fwd + a * right + b * down
        flat = math.hypot(ray[0], ray[1])
        dist = VIEW_RANGE_M if ray[2] >= 0 else min(height_m / -ray[2] * flat, VIEW_RANGE_M)
        pts.append((x_m + ray[0] / flat * dist, y_m + ray[1] / flat * dist))
    return np.array(pts)


def _camera_poses(data: dict, centreline) -> list[tuple[float, float, float, float]]:
    lamps, cam = data["lamps"], data["lamps"]["camera"]
    poses = []
    for p in lamps["poles"]:
        x, y = offset_point(centreline, p["s_m"], p["d_m"])
        along = math.degrees(point_at(centreline, p["s_m"])[2])
        heading = p.get("heading_deg", along + cam.get("heading_deg", 0.0))
        height = cam.get("height_m") or p.get("height_m") or lamps.get("pole_height_m", 6.0)
        poses.append((x, y, height, heading))
    return poses


def blind_stretches_m(data: dict) -> tuple[list[tuple[float, float]], float]:
    """The s intervals (m) of the centreline no camera footprint covers, and the share covered."""
    from matplotlib.path import Path as MplPath

    centreline = [tuple(p) for p in data["street"]["centreline_m"]]
    length = float(cumulative_s(centreline)[-1])
    s = np.arange(0.0, length + 1e-9, STEP_M)
    xy = np.array([point_at(centreline, v)[:2] for v in s])
    seen = np.zeros(len(s), dtype=bool)
    for x, y, h, heading in _camera_poses(data, centreline):
        seen |= MplPath(footprint_m(x, y, h, heading, data["lamps"]["camera"])).contains_points(xy)
    runs, start = [], None
    for v, ok in zip(s, seen, strict=True):
        if not ok and start is None:
            start = v
        elif ok and start is not None:
            runs.append((start, v))
            start = None
    if start is not None:
        runs.append((start, length))
    return runs, float(seen.mean())


def _polyline_at(centreline, d_m: float, s_from: float, s_to: float) -> np.ndarray:
    s = np.append(np.arange(s_from, s_to, STEP_M), s_to)
    return np.array([offset_point(centreline, v, d_m) for v in s])


def draw_street(data: dict, path: str | Path, context_m=()) -> Path:
    """Draw the top-down picture of scenario ``data`` (a mapping as ``scenario_data`` makes) to PNG.

    Parameters
    ----------
    data : the scenario mapping; street.centreline_m and lamps.poles are required.
    path : the PNG to write.
    context_m : other ways to draw in grey, each a sequence of (x_m, y_m) in the same frame.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    street, lamps = data["street"], data["lamps"]
    centreline = [tuple(p) for p in street["centreline_m"]]
    length = float(cumulative_s(centreline)[-1])
    fig, ax = plt.subplots(figsize=(9, 9))
    for way in context_m:
        xy = np.asarray(way)
        ax.plot(xy[:, 0], xy[:, 1], color="0.75", lw=1.5, zorder=1)
    edges = [c + k * w / 2 for c, w in ((x["y_center_m"], x["width_m"]) for x in street["lanes"] + street["sidewalks"])
             for k in (-1, 1)]
    for d in sorted(set(edges)):
        line = _polyline_at(centreline, d, 0.0, length)
        ax.plot(line[:, 0], line[:, 1], color="0.45", lw=0.6, zorder=2)
    colours = plt.cm.tab10(np.arange(len(lamps["poles"])) % 10)
    bounds = zone_bounds_m([p["s_m"] for p in lamps["poles"]], length)
    for (lo, hi), colour in zip(bounds, colours, strict=True):
        band = _polyline_at(centreline, 0.0, lo, hi)
        ax.plot(band[:, 0], band[:, 1], color=colour, lw=7, alpha=0.35, solid_capstyle="butt", zorder=3)
    for (x, y, h, heading), colour in zip(_camera_poses(data, centreline), colours, strict=True):
        poly = footprint_m(x, y, h, heading, lamps["camera"])
        ax.fill(poly[:, 0], poly[:, 1], color=colour, alpha=0.12, zorder=2)
    ax.plot(*np.asarray(centreline).T, color="black", lw=1.2, zorder=4)
    blind, covered = blind_stretches_m(data)
    for lo, hi in blind:
        run = _polyline_at(centreline, 0.0, lo, hi)
        ax.plot(run[:, 0], run[:, 1], color="red", lw=2.5, zorder=5)
    for i, (p, colour) in enumerate(zip(lamps["poles"], colours, strict=True)):
        x, y = offset_point(centreline, p["s_m"], p["d_m"])
        ax.plot(x, y, "o", color=colour, mec="black", ms=7, zorder=6)
        ax.annotate(str(i), (x, y), xytext=(4, 4), textcoords="offset points", fontsize=8, zorder=7)
    for e in street.get("side_entries", []):
        half = max(abs(v["y_center_m"]) + v["width_m"] / 2 for v in street["lanes"] + street["sidewalks"])
        x, y = offset_point(centreline, e["s_m"], half if e["side"] == "left" else -half)
        ax.plot(x, y, "^", color="purple", ms=9, zorder=6)
        ax.annotate(e.get("name", e["kind"]), (x, y), xytext=(5, -10), textcoords="offset points", fontsize=7,
                    color="purple")
    xy = np.asarray(centreline)
    lo, hi = xy.min(axis=0) - ZOOM_MARGIN_M, xy.max(axis=0) + ZOOM_MARGIN_M
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    ax.set_xlabel("east, m (local frame)")
    ax.set_ylabel("north, m")
    ax.set_title(f"{data['name']}: {len(lamps['poles'])} lamps, zones (bands), camera views to {VIEW_RANGE_M:g} m, "
                 f"blind centreline in red ({covered:.0%} seen)", fontsize=9)
    source = street.get("source", "")
    ax.text(0.01, 0.01, source if "OpenStreetMap" not in source else "Map data (c) OpenStreetMap contributors, ODbL 1.0",
            transform=ax.transAxes, fontsize=7, color="0.3")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path
