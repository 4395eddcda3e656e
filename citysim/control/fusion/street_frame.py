"""The one place ground (x, y) becomes street (s, d) and back: every fusion module works in (s, d).

Conventions: ground x east, y north, metres (``Street``'s world frame); street s metres along
the centreline from its start, d metres to its left. Today's streets are straight along x, so
s = x and d = y; a curved street swaps this class alone (its ``to_street``, ``to_ground`` and
``jacobian``), and every tracker, view and controller above it keeps working in (s, d).
"""

from __future__ import annotations

import numpy as np


class StreetFrame:
    """Ground <-> street coordinates of one street (straight along x: s = x, d = y).

    Parameters
    ----------
    length_m : float
        The street's length along its centreline, m (s runs from 0 to it).
    """

    def __init__(self, length_m: float):
        self.length_m = float(length_m)

    @classmethod
    def of(cls, street) -> StreetFrame:
        """The frame of a ``citysim.world.street.Street``."""
        return cls(street.length_m)

    def to_street(self, x_m: float, y_m: float) -> tuple[float, float]:
        """Street (s, d) of ground point (x, y), m."""
        return float(x_m), float(y_m)

    def to_ground(self, s_m: float, d_m: float) -> tuple[float, float]:
        """Ground (x, y) of street point (s, d), m."""
        return float(s_m), float(d_m)

    def jacobian(self, x_m: float, y_m: float) -> np.ndarray:
        """d(s, d) / d(x, y) at ground point (x, y): (2, 2), turns a ground covariance into the street's."""
        return np.eye(2)

    def on_street(self, s_m: float, margin_m: float = 0.0) -> bool:
        """Whether ``s_m`` lies on the street, ``margin_m`` beyond either end allowed."""
        return -margin_m <= s_m <= self.length_m + margin_m
