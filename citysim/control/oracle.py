"""The perfect-knowledge bound: lamps lit exactly where and when people are going to be.

``Oracle`` knows every road user's position and velocity. A lamp goes to full one ramp time
before a target enters its zone (wherever its current velocity, and its kind's greatest
acceleration, could take it within that time, plus two physics steps of margin, since it decides
once a step) and stays lit while a target is in the zone, plus the hold time once the last one
has left. The acceleration matters for a car setting off a few metres before a zone: its speed
alone says it arrives later than it does (measured: a car stopped 3 m short of a zone entered it
13 ms before its lamp was full, once in 12 whole nights). No controller can save more without
leaving someone in the dark: every run compares against it (``savings_vs_oracle``). It pays the
sensing power like any smart lamp, so the bound is one a smart lamp could reach.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from citysim.config.kinds import AGENT_KINDS, TARGET_KINDS
from citysim.control.base import ControlContext, Controller
from citysim.world.agents import AgentState
from citysim.world.approaches import oracle_lead_s
from citysim.world.street import MAX_MASK_ZONES

#: each kind's greatest acceleration (its driver model's, m/s^2): how much sooner than its speed
#: says a road user setting off can reach a zone
_ACCEL_MPS2 = {name: kind.motion.accel_mps2 for name, kind in AGENT_KINDS.items()}


class Oracle(Controller):
    """Full level from one ramp time before each zone entry until exit plus hold."""

    name = "oracle"

    def __init__(self, ctx: ControlContext):
        super().__init__(ctx)
        self.zone_start_m = np.array([s.zone_start_m for s in ctx.street.lamps])
        self.zone_end_m = np.array([s.zone_end_m for s in ctx.street.lamps])
        # dim -> full takes (1 - dim) of a full swing; two of the world's steps of margin (it decides once a step)
        self.lead_s = oracle_lead_s(ctx.luminaire, ctx.physics_step_s)
        # replayed steps (``citysim.sim.recorded``): each step's zones needed, one numpy pass a chunk
        self._by_chunk = len(self.zone_start_m) <= MAX_MASK_ZONES
        self._needed_chunk: tuple[object, list[list[int]]] | None = None

    def zones_needed(self, agents: Sequence[AgentState]) -> np.ndarray:
        """Indices of the zones a target is in, or enters within ``lead_s`` at its current velocity.

        A target is in a zone when its ground centre x lies in [zone_start_m, zone_end_m), the
        rule the zone metrics use.
        """
        targets = [a for a in agents if a.is_target]
        if not targets:
            return np.zeros(0, dtype=np.int64)
        x_m = np.array([a.x_m for a in targets])
        speed_mps = [a.speed_mps for a in targets]
        accel_mps2 = [_ACCEL_MPS2[a.cls] for a in targets]
        return np.flatnonzero(self._touching(x_m, speed_mps, [a.heading_rad for a in targets], accel_mps2).any(axis=0))

    def _touching(self, x_m: np.ndarray, speed_mps: list[float], heading_rad: list[float],
                  accel_mps2: list[float]) -> np.ndarray:  # fmt: skip
        """(targets, zones): whether the zone holds a point between each target and the farthest
        it can go along its heading in ``lead_s`` (speed times lead plus half its greatest
        acceleration times lead squared), measured along x."""
        lead_s = self.lead_s
        ahead_m = np.array([math.cos(h) * (v * lead_s + 0.5 * a * lead_s * lead_s)
                            for v, h, a in zip(speed_mps, heading_rad, accel_mps2, strict=True)])  # fmt: skip
        lo_m, hi_m = np.minimum(x_m, x_m + ahead_m), np.maximum(x_m, x_m + ahead_m)
        return (self.zone_start_m[None, :] <= hi_m[:, None]) & (self.zone_end_m[None, :] > lo_m[:, None])

    def needed_by_step(self, chunk) -> list[list[int]]:
        """Per step of a replayed ``chunk`` (``citysim.sim.recorded.RecordedChunk``): the lamps
        ``zones_needed`` gives for its agents, computed for every row of the chunk at once."""
        if self._needed_chunk is None or self._needed_chunk[0] is not chunk:
            targets = np.flatnonzero(chunk.of_kinds(TARGET_KINDS))
            accel_mps2 = np.array([_ACCEL_MPS2[look.cls] for look in chunk.object_looks])[chunk.object_index]
            touching = self._touching(chunk.column("x_m")[targets], chunk.column("speed_mps")[targets].tolist(),
                                      chunk.column("heading_rad")[targets].tolist(), accel_mps2[targets].tolist())  # fmt: skip
            bits = np.left_shift(np.int64(1), np.arange(len(self.zone_start_m), dtype=np.int64))
            masks = np.zeros(chunk.n_steps, dtype=np.int64)  # per step, bit j: zone j needed
            np.bitwise_or.at(masks, chunk.step_of_row[targets], (touching * bits).sum(axis=1))
            lamps = {m: [j for j in range(len(self.zone_start_m)) if m >> j & 1] for m in set(masks.tolist())}
            self._needed_chunk = (chunk, [lamps[m] for m in masks.tolist()])
        return self._needed_chunk[1]

    def on_physics_step(self, t_s: float, agents: Sequence[AgentState]) -> None:
        super().on_physics_step(t_s, agents)
        chunk = getattr(agents, "chunk", None)  # a replayed step's agents carry their chunk
        if chunk is not None and self._by_chunk:
            needed = self.needed_by_step(chunk)[agents.step]
        else:
            needed = self.zones_needed(agents).tolist()
        self.bank.trigger_all(needed, t_s)
