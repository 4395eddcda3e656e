"""``oracle_seen``: the oracle restricted to what a perfect detector in the scenario's cameras could see.

A road user inside some camera's view (``citysim.control.fusion.views``: between the frame's
bottom row and the detector's 25 m, within the field of view) is known exactly, as the oracle
knows it; one outside every view is known only as it was last seen, carried on from there at its
last speed and heading; one no camera has seen yet is unknown. The lamps are then switched by the
oracle's own rule (``citysim.control.oracle``) on what is known. So each run splits a controller's
gap to the oracle's savings in two: oracle to oracle_seen is what no camera can see (the
cameras' layout), oracle_seen to the controller is what its cameras saw and it did not use.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from citysim.control.base import ControlContext, Controller
from citysim.control.fusion.street_frame import StreetFrame
from citysim.control.fusion.views import CameraViews
from citysim.control.oracle import Oracle
from citysim.world.agents import AgentState


class OracleSeen(Oracle):
    """The oracle on what a perfect detector in the scenario's cameras could know."""

    name = "oracle_seen"

    def __init__(self, ctx: ControlContext):
        super().__init__(ctx)
        self.views = CameraViews([site.camera for site in ctx.street.cameras], StreetFrame.of(ctx.street))
        self.last_seen: dict[int, tuple[float, AgentState]] = {}  # object id -> (time, state) last seen

    def known(self, t_s: float, agents: Sequence[AgentState]) -> list[AgentState]:
        """The targets as a perfect detector in the cameras knows them at ``t_s``: seen now as they
        are, seen before as last seen carried on at their last velocity; never seen: left out."""
        targets = [a for a in agents if a.is_target]
        if not targets:
            self.last_seen.clear()
            return []
        seen = self.views.seen_xy(np.array([[a.x_m, a.y_m] for a in targets])).any(axis=1).tolist()
        present, out = set(), []
        for agent, in_view in zip(targets, seen, strict=True):
            present.add(agent.object_id)
            if in_view:
                self.last_seen[agent.object_id] = (t_s, agent)
                out.append(agent)
                continue
            last = self.last_seen.get(agent.object_id)
            if last is None:
                continue
            t_last, was = last
            gone_m = was.speed_mps * (t_s - t_last)
            out.append(replace(was, x_m=was.x_m + gone_m * math.cos(was.heading_rad),
                               y_m=was.y_m + gone_m * math.sin(was.heading_rad)))  # fmt: skip
        for object_id in [k for k in self.last_seen if k not in present]:
            del self.last_seen[object_id]
        return out

    def on_physics_step(self, t_s: float, agents: Sequence[AgentState]) -> None:
        Controller.on_physics_step(self, t_s, agents)  # the hold's release; not the oracle's whole-chunk path
        self.bank.trigger_all(self.zones_needed(self.known(t_s, agents)).tolist(), t_s)
