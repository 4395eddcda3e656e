"""False on-time: lamp-seconds lit above the idle level while no target is in the lamp's zone.

The energy a controller spends on nobody (insects, branches, animals, lights left on too long).
"""

from __future__ import annotations

import bisect
from collections.abc import Sequence
from typing import Any

import numpy as np

from citysim.config.kinds import TARGET_KINDS
from citysim.metrics.collector import Collector
from citysim.metrics.recorded_rows import recorded_step, step_masks, zone_of
from citysim.world.agents import AgentState
from citysim.world.street import MAX_MASK_ZONES, Street


class FalseOnTime(Collector):
    """Sums ``dt_s`` per lamp that is lit above ``dim_level`` with no target in its zone."""

    def __init__(self, street: Street, dim_level: float, dt_s: float):
        # plain lists: a few lamps and targets per step, where numpy's per-call cost was most of a
        # fast run's metrics
        self.starts_m = [s.zone_start_m for s in street.lamps]
        self.ends_m = [s.zone_end_m for s in street.lamps]
        # zones in lamp order, each ending before the next starts (every street's): the zone a point
        # is in is then the last one starting at or before it, found by bisection
        bounds_m = [x for zone in zip(self.starts_m, self.ends_m, strict=True) for x in zone]
        self._ordered = all(a <= b for a, b in zip(bounds_m[:-1], bounds_m[1:], strict=True))
        # replayed steps: the zones each step's targets occupy, as a bitmask, one numpy pass a chunk
        self._masks = self._ordered and len(self.starts_m) <= MAX_MASK_ZONES
        self._occupied_chunk: tuple[object, list[int]] | None = None
        self.dim_level = dim_level
        self.dt_s = dt_s
        self.seconds = 0.0
        self._levels_seen: np.ndarray | None = None
        self._lit_lamps: list[int] = []
        self._lit_mask = 0  # ``_lit_lamps`` as a bitmask (bit j: lamp j)

    def on_step(self, t_s: float, agents: Sequence[AgentState], levels: np.ndarray) -> None:
        if levels is not self._levels_seen:
            self._lit_lamps = np.flatnonzero(levels > self.dim_level + 1e-6).tolist()
            self._lit_mask = sum(1 << j for j in self._lit_lamps)
            # a read-only array is ``LampStates``' shared one: its lit lamps hold while it is passed again
            self._levels_seen = None if levels.flags.writeable else levels
        if not self._lit_lamps:  # nothing lit: nothing to add
            return
        recorded = recorded_step(agents) if self._masks else None
        if recorded is not None:  # lit lamps less those whose zone holds a target
            unoccupied = (self._lit_mask & ~self._occupied(recorded[0])[recorded[1]]).bit_count()
            self.seconds += self.dt_s * float(unoccupied)
            return
        target_x_m = [a.x_m for a in agents if a.is_target]
        if not target_x_m:  # nobody to light for: every lit lamp is on for nobody
            unoccupied = len(self._lit_lamps)
        elif self._ordered:
            occupied = self._occupied_zones(target_x_m)
            unoccupied = sum(1 for j in self._lit_lamps if j not in occupied)
        else:
            starts, ends = self.starts_m, self.ends_m
            unoccupied = sum(1 for j in self._lit_lamps if not any(starts[j] <= x < ends[j] for x in target_x_m))
        self.seconds += self.dt_s * float(unoccupied)

    def _occupied(self, chunk) -> list[int]:
        """Per step of a replayed ``chunk``: the bitmask of the zones holding a target."""
        if self._occupied_chunk is None or self._occupied_chunk[0] is not chunk:
            zone = zone_of(np.array(self.starts_m), np.array(self.ends_m), chunk.column("x_m"))
            zone[~chunk.of_kinds(TARGET_KINDS)] = -1
            self._occupied_chunk = (chunk, step_masks(chunk, zone))
        return self._occupied_chunk[1]

    def _occupied_zones(self, x_m: list[float]) -> set[int]:
        """The zones (ordered, ``self._ordered``) holding any of the points ``x_m``."""
        occupied = set()
        for x in x_m:
            j = bisect.bisect_right(self.starts_m, x) - 1
            if j >= 0 and x < self.ends_m[j]:
                occupied.add(j)
        return occupied

    def finish(self, t_end_s: float) -> dict[str, Any]:
        return {"false_on_time_s": self.seconds}
