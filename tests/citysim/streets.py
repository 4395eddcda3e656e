"""The street of the citysim tests' tiny scenarios."""

from __future__ import annotations


def two_way_street(length_m: float, **more) -> dict:
    """A scenario's ``street``: one 3.2 m lane each way between two 2.2 m sidewalks, plus ``more``."""
    return {
        "length_m": length_m,
        "lanes": [
            {"y_center_m": -1.6, "width_m": 3.2, "direction": 1},
            {"y_center_m": 1.6, "width_m": 3.2, "direction": -1},
        ],
        "sidewalks": [{"y_center_m": -4.3, "width_m": 2.2}, {"y_center_m": 4.3, "width_m": 2.2}],
        **more,
    }
