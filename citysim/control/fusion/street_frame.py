"""The one place ground (x, y) becomes street (s, d) and back: every fusion module works in (s, d).

Conventions: ground x east, y north, metres (``Street``'s world frame); street s metres along
the centreline from its start, d metres to its left (``citysim.world.centreline``). On the
straight street along +x, s = x and d = y and the conversions return their inputs.
"""

from __future__ import annotations

import math

import numpy as np

from citysim.world.centreline import Centreline


class StreetFrame:
    """Ground <-> street coordinates of one street, through its centreline.

    Parameters
    ----------
    length_m : float
        The street's length along its centreline, m (s runs from 0 to it).
    centreline : Centreline, optional
        The street's centreline in the world frame; None: the straight street along +x.
    """

    def __init__(self, length_m: float, centreline: Centreline | None = None):
        self.length_m = float(length_m)
        self.centreline = centreline if centreline is not None else Centreline.straight(self.length_m)

    @classmethod
    def of(cls, street) -> StreetFrame:
        """The frame of a ``citysim.world.street.Street``."""
        return cls(street.length_m, street.centreline)

    def to_street(self, x_m: float, y_m: float) -> tuple[float, float]:
        """Street (s, d) of ground point (x, y), m."""
        s_m, d_m = self.centreline.to_sd(float(x_m), float(y_m))
        return float(s_m), float(d_m)

    def to_ground(self, s_m: float, d_m: float) -> tuple[float, float]:
        """Ground (x, y) of street point (s, d), m."""
        x_m, y_m = self.centreline.to_xy(float(s_m), float(d_m))
        return float(x_m), float(y_m)

    def jacobian(self, x_m: float, y_m: float) -> np.ndarray:
        """d(s, d) / d(x, y) at ground point (x, y): (2, 2), turns a ground covariance into the
        street's. The rotation into the street's local axes (the curvature's stretch of s with d,
        under 1 % within 5 m of a centreline bending on a 30 m radius or wider, is left out)."""
        if self.centreline.is_straight_x:
            return np.eye(2)
        s_m, _ = self.to_street(x_m, y_m)
        h = self.centreline.heading_rad(float(s_m))
        c, s = math.cos(h), math.sin(h)
        return np.array([[c, s], [-s, c]])

    def on_street(self, s_m: float, margin_m: float = 0.0) -> bool:
        """Whether ``s_m`` lies on the street, ``margin_m`` beyond either end allowed."""
        return -margin_m <= s_m <= self.length_m + margin_m
