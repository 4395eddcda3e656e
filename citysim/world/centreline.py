"""The street's centreline: conversions between street coordinates (s, d) and the world (x, y).

Conventions: world x east, y north, metres; ``s`` metres along the centreline from its
first point, ``d`` metres to the LEFT of it looking along increasing ``s``; headings in radians
counter-clockwise from +x. Beyond its ends the centreline continues straight along its first and
last segments, with cross-sections square to them, so s < 0 and s > length_m map too (agents enter
and leave there).

Off the centreline, the cross-sections are square to the segment, except within ``BLEND_M`` (at
most half the segment) of a bent vertex, where they turn linearly in s to the mitre direction (the
bisector of the turn): the map is continuous round a bend on both sides, a point d to the left of
a vertex lies on the bisector ``d / cos(turn / 2)`` from it, and the distance of any point from its
segment's line is exactly its ``d``. It is one to one while, on the inside of a bend,
``|d| < blend / tan(turn / 2)`` (30 m at a 90-degree bend between segments of 60 m or more).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

#: Round a vertex the cross-sections turn over this much street on either side of it (at most half
#: a segment), m: beyond it they are square to the segment.
BLEND_M = 30.0


@dataclass(frozen=True)
class Centreline:
    """A polyline of ``points_m`` ((x, y) world metres, >= 2 points, distinct neighbours)."""

    points_m: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        if len(self.points_m) < 2:
            raise ValueError(f"a centreline needs >= 2 points, got {len(self.points_m)}")
        lengths = np.hypot(*np.diff(np.asarray(self.points_m, dtype=np.float64), axis=0).T)
        if np.any(lengths <= 0):
            raise ValueError("a centreline's consecutive points must differ")

    @classmethod
    def straight(cls, length_m: float) -> Centreline:
        """The street along +x from (0, 0): s = x, d = y."""
        return cls(((0.0, 0.0), (float(length_m), 0.0)))

    @cached_property
    def _pieces(self) -> tuple[np.ndarray, ...]:
        """The polyline cut into straight pieces: each segment's blend near each bent vertex
        (``BLEND_M``, at most half the segment) and its square middle. Per piece (P pieces): start
        point (P, 2), unit direction (P, 2), length (P,), s at its start (P + 1,), and the
        cross-section vectors at its start and end (P, 2 each): the left normal, or at a vertex its
        mitre (the vector projecting to 1 on both adjacent normals)."""
        pts = np.asarray(self.points_m, dtype=np.float64)
        seg = np.diff(pts, axis=0)
        lengths = np.hypot(seg[:, 0], seg[:, 1])
        units = seg / lengths[:, None]
        normals = np.column_stack([-units[:, 1], units[:, 0]])
        mitres = normals[:-1] + normals[1:]
        mitres = mitres / (1.0 + np.einsum("ij,ij->i", normals[:-1], normals[1:]))[:, None]
        at_vertex = np.vstack([normals[:1], mitres, normals[-1:]])
        bent = np.concatenate([[False], np.abs(np.einsum("ij,ij->i", normals[:-1], normals[1:]) - 1.0) > 1e-12, [False]])
        rows = []  # (start, unit, length, cross-section at start, at end)
        for k, length in enumerate(lengths.tolist()):
            blend = min(BLEND_M, length / 2)
            cuts = [0.0, blend if bent[k] else 0.0, length - blend if bent[k + 1] else length, length]
            vectors = [at_vertex[k], normals[k], normals[k], at_vertex[k + 1]]
            for j in range(3):
                if cuts[j + 1] > cuts[j]:
                    rows.append((pts[k] + cuts[j] * units[k], units[k], cuts[j + 1] - cuts[j], vectors[j], vectors[j + 1]))
        start, unit, piece_m, a, b = (np.array(col, dtype=np.float64) for col in zip(*rows, strict=True))
        return start, unit, piece_m, np.concatenate([[0.0], np.cumsum(piece_m)]), a, b

    @cached_property
    def _rows(self) -> tuple[list, ...]:
        """``_pieces`` as Python lists (start, unit, length, s at start, a, b, heading rad), for one
        point at a time: a float's conversion is then a few float operations, not numpy calls."""
        start, unit, piece_m, cum, a, b = self._pieces
        heading = np.arctan2(unit[:, 1], unit[:, 0])
        return (start.tolist(), unit.tolist(), piece_m.tolist(), cum.tolist(), a.tolist(), b.tolist(),
                heading.tolist())  # fmt: skip

    def _piece_of(self, s_m: float) -> int:
        cum = self._rows[3]
        return min(max(bisect.bisect_right(cum, s_m) - 1, 0), len(cum) - 2)

    def _xy_of(self, s_m: float, d_m: float) -> tuple[float, float]:
        """``to_xy`` of one point, in floats."""
        start, unit, piece_m, cum, a, b, _ = self._rows
        k = self._piece_of(s_m)
        ds = s_m - cum[k]
        t = min(max(ds / piece_m[k], 0.0), 1.0)
        nx = (1.0 - t) * a[k][0] + t * b[k][0]
        ny = (1.0 - t) * a[k][1] + t * b[k][1]
        return start[k][0] + ds * unit[k][0] + d_m * nx, start[k][1] + ds * unit[k][1] + d_m * ny

    def _sd_of(self, x_m: float, y_m: float) -> tuple[float, float]:
        """``to_sd`` of one point, in floats."""
        start, unit, piece_m, cum, a, b, _ = self._rows
        last = len(piece_m) - 1
        best = (math.inf, 0.0, 0.0)
        for k in range(last + 1):
            (px, py), (ux, uy) = start[k], unit[k]
            dx, dy = x_m - px, y_m - py
            along, d = dx * ux + dy * uy, -dx * uy + dy * ux
            if abs(d) >= best[0]:
                continue
            if k == 0 and along < 0 or k == last and along > piece_m[k]:
                t = along / piece_m[k]  # beyond the ends: square cross-sections
            else:
                alpha, beta = a[k][0] * ux + a[k][1] * uy, b[k][0] * ux + b[k][1] * uy
                denom = piece_m[k] + d * (beta - alpha)
                if not denom > 0:
                    continue
                t = (along - d * alpha) / denom
                if not 0.0 <= t <= 1.0:
                    continue
            best = (abs(d), cum[k] + t * piece_m[k], d)
        return best[1], best[2]

    @cached_property
    def is_straight_x(self) -> bool:
        """True for the street along +x from (0, 0) (every point on y = 0, x increasing): the
        conversions are then the identity and return their inputs unchanged."""
        pts = np.asarray(self.points_m, dtype=np.float64)
        return bool(pts[0, 0] == 0.0 and np.all(pts[:, 1] == 0.0) and np.all(np.diff(pts[:, 0]) > 0))

    @property
    def length_m(self) -> float:
        """Polyline length, m."""
        return float(self._pieces[3][-1])

    def _piece(self, s_m: np.ndarray) -> np.ndarray:
        cum = self._pieces[3]
        return np.clip(np.searchsorted(cum, s_m, side="right") - 1, 0, len(cum) - 2)

    def heading_rad(self, s_m):
        """The street direction (toward increasing s) at ``s_m``, rad CCW from +x; at a vertex the
        segment after it. Vectorised over arrays; a float for a float."""
        if self.is_straight_x:
            return np.zeros(np.shape(s_m)) if np.ndim(s_m) else 0.0
        if isinstance(s_m, float):
            return self._rows[6][self._piece_of(s_m)]
        u = self._pieces[1][self._piece(np.asarray(s_m, dtype=np.float64))]
        out = np.arctan2(u[..., 1], u[..., 0])
        return out if np.ndim(s_m) else float(out)

    def to_xy(self, s_m, d_m):
        """World (x, y) m of street coordinates (``s_m``, ``d_m``); arrays broadcast, floats give floats."""
        if self.is_straight_x:
            return s_m, d_m
        if isinstance(s_m, float) and isinstance(d_m, float):  # one point: floats, no numpy
            return self._xy_of(s_m, d_m)
        start, unit, piece_m, cum, a, b = self._pieces
        s = np.asarray(s_m, dtype=np.float64)
        d = np.asarray(d_m, dtype=np.float64)
        k = self._piece(s)
        t = np.clip((s - cum[k]) / piece_m[k], 0.0, 1.0)  # beyond the ends: the end normal
        normal = (1.0 - t)[..., None] * a[k] + t[..., None] * b[k]
        xy = start[k] + (s - cum[k])[..., None] * unit[k] + d[..., None] * normal
        if np.ndim(xy) == 1:
            return float(xy[0]), float(xy[1])
        return xy[..., 0], xy[..., 1]

    def to_sd(self, x_m, y_m):
        """Street coordinates (s, d) m of world points (``x_m``, ``y_m``): of the pieces whose
        stretch (the first and last extended beyond the ends) holds the point, the one it is
        nearest (smallest |d|). Arrays broadcast; floats give floats."""
        if self.is_straight_x:
            return x_m, y_m
        if isinstance(x_m, float) and isinstance(y_m, float):  # one point: floats, no numpy
            return self._sd_of(x_m, y_m)
        start, u, piece_m, cum, a, b = self._pieces
        x = np.asarray(x_m, dtype=np.float64)
        y = np.asarray(y_m, dtype=np.float64)
        shape = np.broadcast(x, y).shape
        px = np.broadcast_to(x, shape).reshape(-1, 1) - start[None, :, 0]
        py = np.broadcast_to(y, shape).reshape(-1, 1) - start[None, :, 1]
        along = px * u[:, 0] + py * u[:, 1]
        d = -px * u[:, 1] + py * u[:, 0]
        alpha = np.einsum("ij,ij->i", a, u)
        beta = np.einsum("ij,ij->i", b, u)
        denom = piece_m + d * (beta - alpha)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (along - d * alpha) / denom
        ok = (denom > 0) & (t >= 0) & (t <= 1)
        # beyond the ends the cross-sections are the end normals: s is the plain distance along
        before, after = along[:, 0] < 0, along[:, -1] > piece_m[-1]
        t[:, 0] = np.where(before, along[:, 0] / piece_m[0], t[:, 0])
        t[:, -1] = np.where(after, along[:, -1] / piece_m[-1], t[:, -1])
        ok[:, 0] |= before
        ok[:, -1] |= after
        best = np.argmin(np.where(ok, np.abs(d), np.inf), axis=1)
        rows = np.arange(len(best))
        s = cum[best] + t[rows, best] * piece_m[best]
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
        c, s = (math.cos(h), math.sin(h)) if isinstance(h, float) else (np.cos(h), np.sin(h))
        return c * dx_m - s * dy_m, s * dx_m + c * dy_m

    def unrotate(self, s_m, vx_m, vy_m):
        """A world vector (``vx_m``, ``vy_m``) at ``s_m`` in the street frame (along +s, to the left)."""
        if self.is_straight_x:
            return vx_m, vy_m
        h = self.heading_rad(s_m)
        c, s = (math.cos(h), math.sin(h)) if isinstance(h, float) else (np.cos(h), np.sin(h))
        return c * vx_m + s * vy_m, -s * vx_m + c * vy_m


def wrap_rad(angle_rad: float) -> float:
    """``angle_rad`` wrapped into (-pi, pi]."""
    return math.atan2(math.sin(angle_rad), math.cos(angle_rad))
