"""Polyline geometry in a local east/north frame (metres, x east, y north).

Street coordinates follow the scenario contract: s is the distance along the centreline from its
first point, d the offset to the LEFT of the centreline looking toward increasing s (right is
negative). Headings are radians counter-clockwise from +x (east).
"""

from __future__ import annotations

import math

import numpy as np

#: Consecutive centreline points closer than this are merged (the scenario schema rejects them), m.
MIN_POINT_GAP_M = 0.5
#: The sharpest turn the scenario schema accepts at one vertex, deg.
MAX_TURN_DEG = 150.0


def clean_polyline(points: list[tuple[float, float]], min_gap_m: float = MIN_POINT_GAP_M) -> list[tuple[float, float]]:
    """Drop points closer than ``min_gap_m`` (m) to the previous kept point; the last point is kept
    (replacing the previous kept one when they are too close)."""
    kept = [points[0]]
    for p in points[1:]:
        if math.dist(p, kept[-1]) >= min_gap_m:
            kept.append(p)
    if len(kept) > 1 and kept[-1] != points[-1]:
        kept[-1] = points[-1]
    return kept


def cumulative_s(points: list[tuple[float, float]]) -> np.ndarray:
    """s (m) at each point of the polyline: 0 at the first, the polyline length at the last."""
    xy = np.asarray(points, dtype=float)
    return np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])


def project(points: list[tuple[float, float]], p: tuple[float, float]) -> tuple[float, float, float]:
    """Project point ``p`` (x, y in m) onto the polyline.

    Returns
    -------
    (s_m, d_m, beyond_m): s of the nearest point on the polyline, the signed offset d (left +),
    and how far the foot of the perpendicular lies beyond the polyline's ends (0 inside), m.
    """
    xy = np.asarray(points, dtype=float)
    a, b = xy[:-1], xy[1:]
    ab = b - a
    length2 = np.einsum("ij,ij->i", ab, ab)
    t_raw = np.einsum("ij,ij->i", np.asarray(p) - a, ab) / length2
    t = np.clip(t_raw, 0.0, 1.0)
    foot = a + t[:, None] * ab
    dist = np.hypot(*(np.asarray(p) - foot).T)
    i = int(np.argmin(dist))
    s = cumulative_s(points)
    seg = math.sqrt(length2[i])
    cross = ab[i, 0] * (p[1] - a[i, 1]) - ab[i, 1] * (p[0] - a[i, 0])
    beyond = 0.0
    if i == 0 and t_raw[0] < 0:
        beyond = -t_raw[0] * seg
    elif i == len(ab) - 1 and t_raw[-1] > 1:
        beyond = (t_raw[-1] - 1.0) * seg
    d = math.copysign(float(dist[i]), cross) if dist[i] > 0 else 0.0
    return float(s[i] + t[i] * seg), d, beyond


def point_at(points: list[tuple[float, float]], s_m: float) -> tuple[float, float, float]:
    """The point (x_m, y_m) at distance ``s_m`` along the polyline (clamped to its ends) and the
    heading of its segment there (rad, CCW from +x)."""
    xy = np.asarray(points, dtype=float)
    s = cumulative_s(points)
    i = int(np.clip(np.searchsorted(s, s_m, side="right") - 1, 0, len(xy) - 2))
    seg = s[i + 1] - s[i]
    t = min(max((s_m - s[i]) / seg, 0.0), 1.0)
    x, y = xy[i] + t * (xy[i + 1] - xy[i])
    dx, dy = xy[i + 1] - xy[i]
    return float(x), float(y), math.atan2(dy, dx)


def offset_point(points: list[tuple[float, float]], s_m: float, d_m: float) -> tuple[float, float]:
    """World (x_m, y_m) of street coordinates (s_m, d_m): d to the left of the segment at s."""
    x, y, heading = point_at(points, s_m)
    return x - d_m * math.sin(heading), y + d_m * math.cos(heading)


def sharpest_turn_deg(points: list[tuple[float, float]]) -> tuple[float, int]:
    """The largest change of direction at one vertex (deg, 0 = straight on, 180 = reversal) and
    that vertex's index (0 when the polyline has no inner vertex)."""
    xy = np.asarray(points, dtype=float)
    if len(xy) < 3:
        return 0.0, 0
    h = np.arctan2(*np.diff(xy, axis=0).T[::-1])
    turn = np.degrees(np.abs((np.diff(h) + np.pi) % (2 * np.pi) - np.pi))
    i = int(np.argmax(turn))
    return float(turn[i]), i + 1


def _crosses(p1, p2, q1, q2) -> bool:
    """Whether the closed segments p1-p2 and q1-q2 share a point (orientation test)."""

    def orient(a, b, c) -> float:
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])

    d1, d2 = orient(q1, q2, p1), orient(q1, q2, p2)
    d3, d4 = orient(p1, p2, q1), orient(p1, p2, q2)
    return (d1 * d2 <= 0) and (d3 * d4 <= 0) and not (d1 == d2 == 0 and max(p1[0], p2[0]) < min(q1[0], q2[0]))


def self_intersection(points: list[tuple[float, float]]) -> tuple[float, float] | None:
    """A point (x_m, y_m) where two non-adjacent segments of the polyline meet, or None."""
    n = len(points) - 1
    for i in range(n):
        for j in range(i + 2, n):
            if _crosses(points[i], points[i + 1], points[j], points[j + 1]):
                return points[j]
    return None
