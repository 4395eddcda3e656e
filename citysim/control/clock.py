"""Lamps lit by the clock, with no sensing: conventional always-on and part-night dimming."""

from __future__ import annotations

from citysim.control.base import Controller


class AlwaysOn(Controller):
    """Conventional lighting: every lamp at full level all night, no sensing."""

    name = "always_on"
    senses = False
    initial_level = "full"

    def on_physics_step(self, t_s, agents):
        pass


class Schedule(Controller):
    """Part-night dimming by the clock: the scenario's schedule steps (clock hour -> level).

    Without steps: full until midnight, dim from 00:00 to 05:00, full again after (a common
    part-night regime).
    """

    name = "schedule"
    senses = False
    initial_level = "full"

    def __init__(self, ctx):
        super().__init__(ctx)
        steps = [(s.start_hour, s.level) for s in ctx.spec.schedule]
        self.steps = sorted(steps) if steps else [(0.0, ctx.dim_level), (5.0, 1.0), (18.0, 1.0)]

    def level_at_hour(self, hour: float) -> float:
        """The step in force at a clock hour (the last step of the day wraps past midnight)."""
        level = self.steps[-1][1]
        for start, step_level in self.steps:
            if hour >= start:
                level = step_level
        return level

    def on_physics_step(self, t_s, agents):
        level = self.level_at_hour((self.ctx.start_hour + t_s / 3600.0) % 24.0)
        for lamp in self.ctx.lamps:
            if lamp.target_level != level:
                lamp.set_target(t_s, level)
