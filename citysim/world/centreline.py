"""The street's centreline: conversions between street coordinates (s, d) and the world (x, y).

Conventions (DESIGN.md): world x east, y north, metres; ``s`` metres along the centreline from its
first point, ``d`` metres to the LEFT of it looking along increasing ``s``; headings in radians
counter-clockwise from +x. Beyond its ends the centreline continues straight along its first and
last segments, with cross-sections square to them, so s < 0 and s > length_m map too (agents enter
and leave there).

Off the centreline, a segment's cross-section lines are interpolated between the mitre directions
at its two vertices (the bisectors of the turns), so the map is continuous round a bend on both
sides: a point d to the left of a vertex lies on the bisector, ``d / cos(turn / 2)`` from it, and
the distance of any point from its segment's line is exactly its ``d``. It is one to one while
``|d|`` is smaller than the bend's radius (a bend's inside reaches the vertex at
``|d| = segment length / tan(turn / 2)``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np


@dataclass(frozen=True)
class Centreline:
    """A polyline of ``points_m`` ((x, y) world metres, >= 2 points, distinct neighbours)."""

    points_m: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        if len(self.points_m) < 2:
            raise ValueError(f"a centreline needs >= 2 points, got {len(self.points_m)}")
        if np.any(self._lengths_m <= 0):
            raise ValueError("a centreline's consecutive points must differ")

    @classmethod
    def straight(cls, length_m: float) -> Centreline:
        """The street along +x from (0, 0): s = x, d = y."""
        return cls(((0.0, 0.0), (float(length_m), 0.0)))

    @cached_property
    def _pts(self) -> np.ndarray:
        return np.asarray(self.points_m, dtype=np.float64)

    @cached_property
    def _lengths_m(self) -> np.ndarray:
        return np.hypot(*np.diff(np.asarray(self.points_m, dtype=np.float64), axis=0).T)

    @cached_property
    def _cum_m(self) -> np.ndarray:
        """s at each point, m."""
        return np.concatenate([[0.0], np.cumsum(self._lengths_m)])

    @cached_property
    def _units(self) -> np.ndarray:
        """(M, 2) unit direction of each segment."""
        return np.diff(self._pts, axis=0) / self._lengths_m[:, None]

    @cached_property
    def _mitres(self) -> np.ndarray:
        """(M + 1, 2): at each point, the vector whose projection on each adjacent segment's left
        normal is 1 (the left normal itself at the ends and where the line runs straight on)."""
        u = self._units
        normals = np.column_stack([-u[:, 1], u[:, 0]])
        inner = normals[:-1] + normals[1:]
        inner = inner / (1.0 + np.einsum("ij,ij->i", normals[:-1], normals[1:]))[:, None]
        return np.vstack([normals[:1], inner, normals[-1:]])

    @cached_property
    def is_straight_x(self) -> bool:
        """True for the street along +x from (0, 0) (every point on y = 0, x increasing): the
        conversions are then the identity and return their inputs unchanged."""
        pts = self._pts
        return bool(pts[0, 0] == 0.0 and np.all(pts[:, 1] == 0.0) and np.all(np.diff(pts[:, 0]) > 0))

    @property
    def length_m(self) -> float:
        """Polyline length, m."""
        return float(self._cum_m[-1])

    def _segment(self, s_m: np.ndarray) -> np.ndarray:
        return np.clip(np.searchsorted(self._cum_m, s_m, side="right") - 1, 0, len(self._lengths_m) - 1)

    def heading_rad(self, s_m):
        """The street direction (toward increasing s) at ``s_m``, rad CCW from +x; at a vertex the
        segment after it. Vectorised over arrays; a float for a float."""
        if self.is_straight_x:
            return np.zeros(np.shape(s_m)) if np.ndim(s_m) else 0.0
        u = self._units[self._segment(np.asarray(s_m, dtype=np.float64))]
        out = np.arctan2(u[..., 1], u[..., 0])
        return out if np.ndim(s_m) else float(out)

    def to_xy(self, s_m, d_m):
        """World (x, y) m of street coordinates (``s_m``, ``d_m``); arrays broadcast, floats give floats."""
        if self.is_straight_x:
            return s_m, d_m
        s = np.asarray(s_m, dtype=np.float64)
        d = np.asarray(d_m, dtype=np.float64)
        k = self._segment(s)
        t = np.clip((s - self._cum_m[k]) / self._lengths_m[k], 0.0, 1.0)  # beyond the ends: the end normal
        normal = (1.0 - t)[..., None] * self._mitres[k] + t[..., None] * self._mitres[k + 1]
        xy = self._pts[k] + (s - self._cum_m[k])[..., None] * self._units[k] + d[..., None] * normal
        if np.ndim(xy) == 1:
            return float(xy[0]), float(xy[1])
        return xy[..., 0], xy[..., 1]

    def to_sd(self, x_m, y_m):
        """Street coordinates (s, d) m of world points (``x_m``, ``y_m``): of the segments whose
        stretch (the first and last extended beyond the ends) holds the point, the one it is
        nearest (smallest |d|). Arrays broadcast; floats give floats."""
        if self.is_straight_x:
            return x_m, y_m
        x = np.asarray(x_m, dtype=np.float64)
        y = np.asarray(y_m, dtype=np.float64)
        shape = np.broadcast(x, y).shape
        px = np.broadcast_to(x, shape).reshape(-1, 1) - self._pts[None, :-1, 0]
        py = np.broadcast_to(y, shape).reshape(-1, 1) - self._pts[None, :-1, 1]
        u = self._units
        along = px * u[:, 0] + py * u[:, 1]
        d = -px * u[:, 1] + py * u[:, 0]
        alpha = np.einsum("ij,ij->i", self._mitres[:-1], u)
        beta = np.einsum("ij,ij->i", self._mitres[1:], u)
        denom = self._lengths_m + d * (beta - alpha)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (along - d * alpha) / denom
        ok = (denom > 0) & (t >= 0) & (t <= 1)
        # beyond the ends the cross-sections are the end normals: s is the plain distance along
        before, after = along[:, 0] < 0, along[:, -1] > self._lengths_m[-1]
        t[:, 0] = np.where(before, along[:, 0] / self._lengths_m[0], t[:, 0])
        t[:, -1] = np.where(after, along[:, -1] / self._lengths_m[-1], t[:, -1])
        ok[:, 0] |= before
        ok[:, -1] |= after
        cost = np.where(ok, np.abs(d), np.inf)
        best = np.argmin(cost, axis=1)
        rows = np.arange(len(best))
        s = self._cum_m[best] + t[rows, best] * self._lengths_m[best]
        d_best = d[rows, best]
        if not shape:
            return float(s[0]), float(d_best[0])
        return s.reshape(shape), d_best.reshape(shape)

    def rotate(self, s_m, dx_m, dy_m):
        """A vector (``dx_m``, ``dy_m``) given in the street frame at ``s_m`` (dx along +s, dy to
        the left) in world axes. Arrays broadcast."""
        if self.is_straight_x:
            return dx_m, dy_m
        h = self.heading_rad(s_m)
        c, s = np.cos(h), np.sin(h)
        return c * dx_m - s * dy_m, s * dx_m + c * dy_m

    def unrotate(self, s_m, vx_m, vy_m):
        """A world vector (``vx_m``, ``vy_m``) at ``s_m`` in the street frame (along +s, to the left)."""
        if self.is_straight_x:
            return vx_m, vy_m
        h = self.heading_rad(s_m)
        c, s = np.cos(h), np.sin(h)
        return c * vx_m + s * vy_m, -s * vx_m + c * vy_m


def wrap_rad(angle_rad: float) -> float:
    """``angle_rad`` wrapped into (-pi, pi]."""
    return math.atan2(math.sin(angle_rad), math.cos(angle_rad))
