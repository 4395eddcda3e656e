"""False on-time: lamp-seconds lit above the idle level while no target is in the lamp's zone.

The energy a controller spends on nobody (insects, branches, animals, lights left on too long).
"""

from __future__ import annotations

import bisect
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
        # per step, on plain lists: a few lamps and targets, where numpy's per-call cost was most
        # of a fast run's metrics (the same comparisons as ``add``, so the same sums bit for bit)
        self._starts_m, self._ends_m = self.starts.tolist(), self.ends.tolist()
        # zones in street order, none overlapping another (the usual street): a target can be in
        # one zone only, the last one starting at or before it, found by bisection
        self._disjoint_in_order = all(
            start <= next_start and end <= next_start
            for start, end, next_start in zip(self._starts_m[:-1], self._ends_m[:-1], self._starts_m[1:], strict=True)
        )
        self._levels_seen: np.ndarray | None = None
        self._lit_lamps: list[int] = []

    def on_step(self, t_s: float, agents: Sequence[AgentState], levels: np.ndarray) -> None:
        if levels is not self._levels_seen:
            self._lit_lamps = np.flatnonzero(levels > self.dim_level + 1e-6).tolist()
            # a read-only array is ``LampStates``' shared one: its lit lamps hold while it is passed again
            self._levels_seen = None if levels.flags.writeable else levels
        if not self._lit_lamps:  # nothing lit: nothing to add
            return
        target_x_m = [a.x_m for a in agents if a.is_target]
        if target_x_m and self._disjoint_in_order:
            occupied = {self._zone_of(x) for x in target_x_m}
            unoccupied = sum(1 for j in self._lit_lamps if j not in occupied)
        elif target_x_m:
            starts, ends = self._starts_m, self._ends_m
            unoccupied = sum(1 for j in self._lit_lamps if not any(starts[j] <= x < ends[j] for x in target_x_m))
        else:  # no zone occupied: every lit lamp counts
            unoccupied = len(self._lit_lamps)
        self.seconds += self.dt_s * float(unoccupied)

    def _zone_of(self, x_m: float) -> int:
        """The zone holding ``x_m`` (-1: none), for zones disjoint and in order."""
        j = bisect.bisect_right(self._starts_m, x_m) - 1
        return j if j >= 0 and x_m < self._ends_m[j] else -1

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
