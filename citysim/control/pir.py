"""A passive-infrared sensor per pole: warm bodies in its cone, no classes (the usual smart lamp)."""

from __future__ import annotations

import math

import numpy as np

from citysim.control.base import Controller

#: PIR reference values: 12 m reach (the upper end of commercial sensors), a 110 deg cone, and a
#: 90% chance per second of seeing a warm body inside it.
PIR_RANGE_M = 12.0
PIR_CONE_DEG = 110.0
PIR_DETECTION_PROBABILITY_PER_S = 0.9


class PassiveInfrared(Controller):
    """A PIR sensor per pole: warm bodies within range in its cone, with a detection probability; no classes.

    Reference values: commercial PIR reaches 3-12 m in a 110-120 deg cone and needs a few degrees of
    thermal contrast; it cannot tell a fox from a pedestrian.
    """

    name = "pir"

    def __init__(self, ctx):
        super().__init__(ctx)
        self.range_m = PIR_RANGE_M
        self.cone_deg = PIR_CONE_DEG
        self.p_detect_per_s = PIR_DETECTION_PROBABILITY_PER_S
        self.period_s = 0.25  # the sensor's output is sampled at 4 Hz
        self.next_sample_s = 0.0
        cams = [lamp.camera for lamp in ctx.street.lamps]
        self.pole_xy_m = np.array([[c.x_m, c.y_m] for c in cams])
        self.heading = np.array([c.heading_unit for c in cams])

    def on_physics_step(self, t_s, agents):
        super().on_physics_step(t_s, agents)
        if t_s < self.next_sample_s or not agents:
            return
        self.next_sample_s = t_s + self.period_s
        chunk = getattr(agents, "chunk", None)  # a replayed step's agents carry their chunk
        if chunk is None:
            xy = np.array([[a.x_m, a.y_m] for a in agents])
        else:  # the step's rows of the chunk's columns: the same numbers, no agent's snapshot made
            rows = slice(agents.first, agents.first + len(agents))
            xy = np.stack([chunk.column("x_m")[rows], chunk.column("y_m")[rows]], axis=1)
        line = self.ctx.street.centreline
        if not line.is_straight_x:  # the sensors stand in the world; agents move in (s, d)
            xy = np.column_stack(line.to_xy(xy[:, 0], xy[:, 1]))
        rel = xy[None, :, :] - self.pole_xy_m[:, None, :]  # lamps x agents x 2
        dist = np.linalg.norm(rel, axis=2)
        cos_angle = np.einsum("lak,lk->la", rel, self.heading) / np.maximum(dist, 1e-9)
        in_cone = (dist <= self.range_m) & (cos_angle >= math.cos(math.radians(self.cone_deg / 2)))
        p = 1.0 - (1.0 - self.p_detect_per_s) ** self.period_s
        seen = in_cone & (self.ctx.rng.random(in_cone.shape) < p)
        for lamp_index in np.flatnonzero(seen.any(axis=1)):
            self.bank.trigger(int(lamp_index), t_s)
