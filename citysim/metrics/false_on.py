"""False on-time: lamp-seconds lit above the idle level while no target is in the lamp's zone.

The energy a controller spends on nobody (insects, branches, animals, lights left on too long).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from citysim.metrics.collector import Collector
from citysim.world.agents import AgentState
from citysim.world.street import Street


class FalseOnTime(Collector):
    """Sums ``dt_s`` per lamp that is lit above ``dim_level`` with no target in its zone."""

    def __init__(self, street: Street, dim_level: float, dt_s: float):
        self.starts = np.array([s.zone_start_m for s in street.lamps])
        self.ends = np.array([s.zone_end_m for s in street.lamps])
        self.dim_level = dim_level
        self.dt_s = dt_s
        self.seconds = 0.0
        self._levels_counted: np.ndarray | None = None
        self._lit_count = 0

    def on_step(self, t_s: float, agents: Sequence[AgentState], levels: np.ndarray) -> None:
        if levels is not self._levels_counted:
            self._lit_count = int(np.count_nonzero(levels > self.dim_level + 1e-6))
            # a read-only array is ``LampStates``' shared one: its count holds while it is passed again
            self._levels_counted = None if levels.flags.writeable else levels
        lit_count = self._lit_count
        if not lit_count:  # nothing lit: add() would add nothing
            return
        target_x_m = [a.x_m for a in agents if a.is_target]
        if not target_x_m:  # no zone occupied: every lit lamp counts, as add() would count it
            self.seconds += self.dt_s * float(lit_count)
            return
        self.add(self.dt_s, np.array(target_x_m), levels)

    def add(self, dt_s: float, target_x_m: np.ndarray, levels: np.ndarray) -> None:
        lit = levels > self.dim_level + 1e-6
        if not lit.any():
            return
        if len(target_x_m):
            inside = (target_x_m[None, :] >= self.starts[:, None]) & (target_x_m[None, :] < self.ends[:, None])
            occupied = inside.any(axis=1)
        else:
            occupied = np.zeros(len(levels), dtype=bool)
        self.seconds += dt_s * float(np.count_nonzero(lit & ~occupied))

    def finish(self, t_end_s: float) -> dict[str, Any]:
        return {"false_on_time_s": self.seconds}
