"""The perfect-knowledge bound: lamps lit exactly where and when people are going to be.

``Oracle`` knows every road user's position and velocity. A lamp goes to full one ramp time
before a target enters its zone (where its current velocity takes it within that time, plus two
physics steps of margin, since it decides once a step) and stays lit while a target is in the
zone, plus the hold time once the last one has left. No controller can save more without
leaving someone in the dark: every run compares against it (``savings_vs_oracle``). It pays the
sensing power like any smart lamp, so the bound is one a smart lamp could reach.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from citysim.control.base import ControlContext, Controller
from citysim.world.agents import AgentState


class Oracle(Controller):
    """Full level from one ramp time before each zone entry until exit plus hold."""

    name = "oracle"

    def __init__(self, ctx: ControlContext):
        super().__init__(ctx)
        self.zone_start_m = np.array([s.zone_start_m for s in ctx.street.lamps])
        self.zone_end_m = np.array([s.zone_end_m for s in ctx.street.lamps])
        lum = ctx.luminaire
        # dim -> full takes (1 - dim) of a full swing; two physics steps of margin at 30 Hz
        self.lead_s = (1.0 - lum.dim_level) * lum.ramp_up_s + 2.0 / 30.0

    def zones_needed(self, agents: Sequence[AgentState]) -> np.ndarray:
        """Indices of the zones a target is in, or enters within ``lead_s`` at its current velocity.

        A target is in a zone when its ground centre x lies in [zone_start_m, zone_end_m), the
        rule the zone metrics use.
        """
        targets = [a for a in agents if a.is_target]
        if not targets:
            return np.zeros(0, dtype=np.int64)
        x_m = np.array([a.x_m for a in targets])
        ahead_m = np.array([a.speed_mps * math.cos(a.heading_rad) for a in targets]) * self.lead_s
        lo_m, hi_m = np.minimum(x_m, x_m + ahead_m), np.maximum(x_m, x_m + ahead_m)
        touching = (self.zone_start_m[:, None] <= hi_m[None, :]) & (self.zone_end_m[:, None] > lo_m[None, :])
        return np.flatnonzero(touching.any(axis=1))

    def on_physics_step(self, t_s: float, agents: Sequence[AgentState]) -> None:
        super().on_physics_step(t_s, agents)
        for lamp_index in self.zones_needed(agents):
            self.bank.trigger(int(lamp_index), t_s)
