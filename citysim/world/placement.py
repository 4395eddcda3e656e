"""Road users placed in the world: agent snapshots from street coordinates to the world frame.

The pymunk world is the straightened street: an ``AgentState``'s ``x_m``/``y_m`` are its s/d and its
``heading_rad`` is CCW from the local +s direction. Everything that looks at the street from a point
in the world (renderer, cameras, PIR sensors, fast mode's projections) takes the snapshots placed
here: world x east, y north (m), heading CCW from +x (rad).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from citysim.world.agents import AgentState, frozen_from_fields
from citysim.world.centreline import Centreline


def agents_in_world(line: Centreline, agents: Sequence[AgentState]) -> Sequence[AgentState]:
    """``agents`` (street coordinates) in the world frame of ``line``; the same sequence, unchanged,
    on the straight street along +x (there s = x, d = y and headings agree)."""
    if line.is_straight_x or not agents:
        return agents
    s_m = np.fromiter((a.x_m for a in agents), np.float64, len(agents))
    d_m = np.fromiter((a.y_m for a in agents), np.float64, len(agents))
    x_m, y_m = line.to_xy(s_m, d_m)
    turn = line.heading_rad(s_m)
    out = []
    for a, x, y, dh in zip(agents, x_m.tolist(), y_m.tolist(), turn.tolist(), strict=True):
        fields = dict(a.__dict__)
        fields["x_m"], fields["y_m"], fields["heading_rad"] = x, y, a.heading_rad + dh
        out.append(frozen_from_fields(AgentState, fields))
    return out


def columns_in_world(line: Centreline, s_m: np.ndarray, d_m: np.ndarray, heading_rad: np.ndarray):
    """World (x_m, y_m, heading_rad) arrays of agents given as street-coordinate columns (s, d m;
    heading rad CCW from +s); the inputs themselves on the straight street along +x."""
    if line.is_straight_x:
        return s_m, d_m, heading_rad
    x_m, y_m = line.to_xy(np.asarray(s_m, np.float64), np.asarray(d_m, np.float64))
    return x_m, y_m, np.asarray(heading_rad, np.float64) + line.heading_rad(np.asarray(s_m, np.float64))
