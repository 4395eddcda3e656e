"""Paths and footprints: the geometry the world's behaviour model works in.

A ``Route`` is a chain of straight ``Leg``s. An agent on a leg is described by
``s`` (metres along the leg from its start) and a lateral ``offset`` (metres to
the left of the leg direction, i.e. counter-clockwise); ``band_m`` bounds the
offsets its centre may take there, ``comfort_m`` is the part it uses without
reluctance (the sidewalk proper, its own lane), ``pref_m`` where it likes to be
(keep right). Footprints are oriented boxes on the ground: centre (x, y),
heading (rad, CCW from +x), length along the heading and width across it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Leg:
    """One straight stretch of a route (world frame, metres)."""

    start_xy_m: tuple[float, float]
    end_xy_m: tuple[float, float]
    band_m: tuple[float, float]
    comfort_m: tuple[float, float]
    pref_m: float
    yield_to_traffic: bool = (
        False  # wait at the start until road users leave a gap (crossing the road)
    )

    def __post_init__(self) -> None:
        if self.length_m <= 0:
            raise ValueError(f"a leg needs distinct start and end, got {self.start_xy_m} twice")
        lo, hi = self.band_m
        if not (lo <= self.comfort_m[0] <= self.comfort_m[1] <= hi and lo <= self.pref_m <= hi):
            raise ValueError(
                f"leg bands must nest: band {self.band_m} >= comfort {self.comfort_m}, pref {self.pref_m} in band"
            )

    @property
    def length_m(self) -> float:
        return math.dist(self.start_xy_m, self.end_xy_m)

    @property
    def unit(self) -> tuple[float, float]:
        """Direction of travel (unit vector)."""
        d = self.length_m
        return (
            (self.end_xy_m[0] - self.start_xy_m[0]) / d,
            (self.end_xy_m[1] - self.start_xy_m[1]) / d,
        )

    @property
    def heading_rad(self) -> float:
        ux, uy = self.unit
        return math.atan2(uy, ux)

    def point(self, s_m: float, offset_m: float) -> tuple[float, float]:
        """World point ``s_m`` along the leg and ``offset_m`` to its left."""
        ux, uy = self.unit
        return (
            self.start_xy_m[0] + s_m * ux - offset_m * uy,
            self.start_xy_m[1] + s_m * uy + offset_m * ux,
        )


@dataclass(frozen=True)
class Route:
    """The legs an agent follows, and the entry it queues at when spawned (agents
    arriving at the same entry enter one after the other)."""

    legs: tuple[Leg, ...]
    entry_key: str

    def __post_init__(self) -> None:
        if not self.legs:
            raise ValueError("a route needs at least one leg")


def oriented_overlaps(
    xy_m: np.ndarray,
    heading_rad: np.ndarray,
    length_m: np.ndarray,
    width_m: np.ndarray,
    margin_m: float = 0.0,
) -> np.ndarray:
    """(N, N) bool: do the footprints of agents i and j overlap (each grown by ``margin_m``)?

    Separating-axis test on oriented boxes; the diagonal is False.
    """
    n = len(xy_m)
    c, s = np.cos(heading_rad), np.sin(heading_rad)
    fwd = np.stack([c, s], axis=1)
    left = np.stack([-s, c], axis=1)
    half_l = length_m / 2 + margin_m
    half_w = width_m / 2 + margin_m
    d = xy_m[None, :, :] - xy_m[:, None, :]  # d[i, j] = x_j - x_i
    separated = np.zeros((n, n), dtype=bool)
    for axes, half in ((fwd, half_l), (left, half_w)):
        # project onto agent i's axis: |d . a_i| against i's half extent + j's projected radius
        dist = np.abs(np.einsum("ijk,ik->ij", d, axes))
        radius_j = half_l[None, :] * np.abs(axes @ fwd.T) + half_w[None, :] * np.abs(axes @ left.T)
        separated |= dist > half[:, None] + radius_j
    separated |= separated.T  # j's axes are i's axes of the transposed pair
    out = ~separated
    np.fill_diagonal(out, False)
    return out
