"""The moving world: agents as pymunk bodies following their routes without overlapping.

Every agent is a *kinematic* pymunk body carrying a box shape (its ground
footprint). Kinematic, not dynamic, because the motion is prescribed by the
behaviour model (``citysim.world.behaviour``: path following, car following,
giving way): a kinematic body follows the velocity it is given exactly, is
never shoved off its sidewalk or lane by a contact impulse, and costs the
solver nothing (Chipmunk does not collide kinematic bodies with each other).
Dynamic bodies would resolve contacts only after they overlap, with some
penetration slop; here overlaps are prevented before they happen. Each step
the behaviour sets every body's velocity and angular velocity and
``Space.step`` integrates the poses.

Agents are spawned into per-entry queues and enter when their entry is free;
they leave at the street ends (or at the end of their route) and are removed
from the space, so memory stays flat. Same street, same spawns, same rng ->
the same trajectories, bit for bit.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Generator
from typing import TYPE_CHECKING

import numpy as np
import pymunk

from citysim.config.kinds import AGENT_KINDS
from citysim.world.agents import AgentState, AgentTraits, MemberState
from citysim.world.behaviour import Layout, Mover, layout_for, plan_moves
from citysim.world.geometry import Leg, Route, oriented_overlaps
from citysim.world.street import Street

if TYPE_CHECKING:
    pass

__all__ = ["Leg", "Route", "World", "physics_process"]

TWO_PI = 2.0 * math.pi
#: Clearance a newcomer needs to everyone at its entry pose, m (the gap ahead is checked apart).
ENTRY_CLEARANCE_M = 0.05


class World:
    """Agents on a street, stepped in fixed time steps.

    ``rng`` drives the choices made while moving (animals stopping to sniff);
    what arrives and where it goes is drawn by ``citysim.world.traffic``.
    """

    def __init__(self, street: Street, rng: np.random.Generator) -> None:
        self.street = street
        self.rng = rng
        self.space = pymunk.Space()
        self.t_s = 0.0
        self._agents: dict[int, Mover] = {}
        self._pending: dict[str, deque[tuple[int, AgentTraits, Route]]] = {}
        self._next_id = 0
        self.spawned_count = 0
        self.removed_count = 0
        self.blocked_moves = 0  # moves the last-resort overlap check cancelled (diagnostic)
        self._layout_cache: Layout | None = None

    # ------------------------------------------------------------------ public
    @property
    def agent_count(self) -> int:
        return len(self._agents)

    @property
    def pending_count(self) -> int:
        return sum(len(q) for q in self._pending.values())

    def spawn(self, traits: AgentTraits, route: Route) -> int:
        """Queue an agent at its route's entry; it enters at the next step the entry is free.

        Returns its object id (ids increase in spawn order).
        """
        if traits.cls not in AGENT_KINDS:
            raise ValueError(f"unknown agent class {traits.cls!r}; valid: {', '.join(AGENT_KINDS)}")
        oid = self._next_id
        self._next_id += 1
        self._pending.setdefault(route.entry_key, deque()).append((oid, traits, route))
        return oid

    def step(self, dt_s: float) -> None:
        """Advance the world by ``dt_s`` seconds (admit queued agents, move, remove leavers)."""
        if not dt_s > 0:
            raise ValueError(f"dt_s must be > 0 s, got {dt_s}")
        self._admit()
        agents = list(self._agents.values())
        if agents:
            self._layout_cache = layout_for(agents, self._layout_cache)
            self.blocked_moves += plan_moves(agents, self._layout_cache, dt_s, self.t_s)
        self.space.step(dt_s)
        if agents:
            self._advance_routes(agents, dt_s)
        self.t_s += dt_s

    def states(self) -> list[AgentState]:
        """Immutable snapshots of all agents in the street, in order of entry."""
        out = []
        for a in self._agents.values():
            x, y = a.body.position
            members = tuple(
                MemberState(m.forward_m, m.left_m, m.width_m, m.height_m, m.length_m, p)
                for m, p in zip(a.traits.members, a.member_phases, strict=True)
            )
            out.append(
                AgentState(
                    object_id=a.oid,
                    cls=a.traits.cls,
                    x_m=float(x),
                    y_m=float(y),
                    heading_rad=(a.body.angle + math.pi) % TWO_PI - math.pi,
                    speed_mps=math.hypot(*a.velocity),
                    length_m=a.traits.length_m,
                    width_m=a.traits.width_m,
                    height_m=a.traits.height_m,
                    gait_phase_rad=a.phase,
                    members=members,
                    light_on=a.traits.light_on,
                )
            )
        return out

    # --------------------------------------------------------------- admission
    def _admit(self) -> None:
        """Let the head of each entry queue in if its footprint and a minimal gap ahead are free."""
        for key in list(self._pending):
            queue = self._pending[key]
            oid, traits, route = queue[0]
            leg = route.legs[0]
            x, y = leg.point(0.0, leg.pref_m)
            heading = leg.heading_rad
            motion = AGENT_KINDS[traits.cls].motion
            speed = traits.desired_speed_mps
            if self._agents:
                others = list(self._agents.values())
                xy = np.array([[x, y]] + [tuple(a.body.position) for a in others])
                th = np.array([heading] + [a.body.angle for a in others])
                ln = np.array([traits.length_m] + [a.traits.length_m for a in others])
                wd = np.array([traits.width_m] + [a.traits.width_m for a in others])
                if oriented_overlaps(xy, th, ln, wd, margin_m=ENTRY_CLEARANCE_M)[0].any():
                    continue
                gap = self._gap_ahead(x, y, leg, traits, others)
                if gap < motion.min_gap_m:
                    continue
                speed = min(speed, max(0.0, (gap - motion.min_gap_m) / motion.headway_s))
            queue.popleft()
            if not queue:
                del self._pending[key]
            body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
            body.position = (x, y)
            body.angle = heading
            shape = pymunk.Poly.create_box(body, (traits.length_m, traits.width_m))
            self.space.add(body, shape)
            agent = Mover(oid, traits, route.legs, body, shape)
            agent.speed_mps = speed
            self._agents[oid] = agent
            self.spawned_count += 1

    @staticmethod
    def _gap_ahead(x: float, y: float, leg: Leg, traits: AgentTraits, others: list[Mover]) -> float:
        """Free distance ahead of a footprint at (x, y) on ``leg``, within its corridor, m."""
        ux, uy = leg.unit
        best = math.inf
        for a in others:
            ox, oy = a.body.position
            f = (ox - x) * ux + (oy - y) * uy
            lat = -(ox - x) * uy + (oy - y) * ux
            reach = max(a.traits.length_m, a.traits.width_m) / 2
            if f > 0 and abs(lat) < reach + traits.width_m / 2 + 0.1:
                best = min(best, f - reach - traits.length_m / 2)
        return best

    # ------------------------------------------------------ after the space stepped
    def _advance_routes(self, agents: list[Mover], dt: float) -> None:
        """After the space stepped: gait phases, leg changes, removal of leavers, pauses (animals)."""
        for a in agents:
            speed = math.hypot(*a.velocity)
            dist = speed * dt
            a.phase = (a.phase + TWO_PI * dist / a.traits.stride_m) % TWO_PI
            if a.member_phases:
                a.member_phases = [
                    (p + TWO_PI * dist / a.traits.stride_m) % TWO_PI for p in a.member_phases
                ]
            held = speed < 0.05 and not a.waiting and a.pause_until_s < self.t_s
            a.still_s = a.still_s + dt if held else 0.0
            x, y = a.body.position
            while True:
                leg = a.leg
                ux, uy = leg.unit
                s = (x - leg.start_xy_m[0]) * ux + (y - leg.start_xy_m[1]) * uy
                if s < leg.length_m:
                    break
                if a.leg_i + 1 == len(a.legs):
                    self._remove(a)
                    break
                a.leg_i += 1
                a.target_m = a.leg.pref_m
            pauses = AGENT_KINDS[a.traits.cls].pauses  # animals stop now and then
            if a.oid in self._agents and pauses is not None and a.pause_until_s < self.t_s:
                if self.rng.random() < dt / pauses.every_s:
                    a.pause_until_s = self.t_s + float(self.rng.uniform(*pauses.duration_s))

    def _remove(self, a: Mover) -> None:
        self.space.remove(a.shape, a.body)
        del self._agents[a.oid]
        self.removed_count += 1

    # ------------------------------------------------------------- diagnostics
    def stuck_agents(self, min_still_s: float = 60.0) -> list[int]:
        """Ids of agents held still for ``min_still_s`` by others (not waiting at a kerb or
        pausing): a behaviour bug if ever non-empty."""
        return [a.oid for a in self._agents.values() if a.still_s >= min_still_s]

    def traits_of(self, object_id: int) -> AgentTraits:
        """How an agent in the street looks and how fast it wants to go."""
        return self._agents[object_id].traits

    def route_leg(self, object_id: int) -> Leg:
        """The leg an agent is on now (tests and debugging)."""
        return self._agents[object_id].leg


def physics_process(env, world: World, physics_hz: float) -> Generator:
    """simpy process stepping ``world`` at ``physics_hz`` (fixed dt, no drift over long runs)."""
    if not physics_hz > 0:
        raise ValueError(f"physics_hz must be > 0, got {physics_hz}")
    dt = 1.0 / physics_hz
    k = 0
    while True:
        k += 1
        yield env.timeout(max(0.0, k * dt - env.now))
        world.step(dt)
