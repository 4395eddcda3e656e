"""Lamps lit by the clock, with no sensing: conventional always-on and part-night dimming."""

from __future__ import annotations

from dataclasses import dataclass

from citysim.config.scenario import ControllerSpec
from citysim.control.base import Controller


class AlwaysOn(Controller):
    """Conventional lighting: every lamp at full level all night, no sensing."""

    name = "always_on"
    senses = False
    initial_level = "full"

    def on_physics_step(self, t_s, agents):
        pass


@dataclass(frozen=True)
class ScheduleSteps:
    """Clock hour -> level steps of a part-night schedule, in start order.

    Without steps in the spec: full until midnight, dim from 00:00 to 05:00, full again after
    (a common part-night regime).
    """

    steps: tuple[tuple[float, float], ...]

    @classmethod
    def of(cls, spec: ControllerSpec, dim_level: float) -> ScheduleSteps:
        steps = sorted((s.start_hour, s.level) for s in spec.schedule)
        return cls(tuple(steps) if steps else ((0.0, dim_level), (5.0, 1.0), (18.0, 1.0)))

    def level_at_hour(self, hour: float) -> float:
        """The step in force at a clock hour (the last step of the day wraps past midnight)."""
        level = self.steps[-1][1]
        for start, step_level in self.steps:
            if hour >= start:
                level = step_level
        return level


class Schedule(Controller):
    """Part-night dimming by the clock: the scenario's schedule steps (see ``ScheduleSteps``)."""

    name = "schedule"
    senses = False
    initial_level = "full"

    def __init__(self, ctx):
        super().__init__(ctx)
        self.schedule = ScheduleSteps.of(ctx.spec, ctx.dim_level)

    def level_at_hour(self, hour: float) -> float:
        return self.schedule.level_at_hour(hour)

    def on_physics_step(self, t_s, agents):
        level = self.level_at_hour((self.ctx.start_hour + t_s / 3600.0) % 24.0)
        for lamp in self.ctx.lamps:
            if lamp.target_level != level:
                lamp.set_target(t_s, level)
