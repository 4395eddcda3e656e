"""The moving world: agents as pymunk bodies following their routes without overlapping.

Every agent is a *kinematic* pymunk body carrying a box shape (its ground footprint) in the
world's ``space`` (``citysim.world.bodies``): its motion is prescribed by the behaviour model
(``citysim.world.behaviour``: path following, car following, giving way), so it follows the
velocity it is given exactly, is never shoved off its sidewalk or lane, and overlaps are prevented
before they happen instead of resolved after. Each step the behaviour, compiled (numba), decides
every agent's move from arrays of the agents' state, one row per agent in order of entry
(``citysim.world.rows``); the moves are handed to the bodies as velocity and angular velocity,
``Space.step`` integrates the poses, and the rows read them back.

Agents are spawned into per-entry queues and enter when their entry is free;
they leave at the street ends (or at the end of their route) and are removed
from the space (and their rows dropped), so memory stays flat. Same street, same spawns, same
rng -> the same trajectories, bit for bit.

Conventions: world frame of docs/design/architecture.md, metres, seconds, m/s; angles rad CCW from +x.
"""

from __future__ import annotations

import functools
import math
from collections import deque
from collections.abc import Callable, Generator

import numpy as np

from citysim.config.kinds import AGENT_KINDS
from citysim.world.agents import AgentState, AgentTraits, MemberState, frozen_from_fields
from citysim.world.bodies import Bodies
from citysim.world.geometry import Leg, Route, oriented_overlaps
from citysim.world.rows import (
    LENGTH,
    N_COLUMNS,
    PAUSE,
    PHASE,
    STILL,
    TARGET,
    TH,
    VEL,
    WIDTH,
    Mover,
    X,
    new_row,
    set_leg,
)
from citysim.world.street import Street

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
        self.t_s = 0.0
        self._bodies = Bodies()  # one pymunk kinematic body per agent, in the rows' order
        self.space = self._bodies.space
        self._agents: dict[int, Mover] = {}
        self._movers: list[Mover] = []  # the same, in order of entry: the rows' order
        self._state = np.zeros((0, N_COLUMNS))  # one row per agent, in order of entry (rows.py)
        self._vu = np.zeros((2, 0, 2))  # velocities and leg directions, same order
        self._pending: dict[str, deque[tuple[int, AgentTraits, Route]]] = {}
        self._next_id = 0
        self.spawned_count = 0
        self.removed_count = 0
        self.blocked_moves = 0  # moves the last-resort overlap check cancelled (diagnostic)

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
        if self._pending:
            self._admit()
        if self._movers:
            move_agents, _ = _compiled()
            self.blocked_moves += move_agents(self._state, self._vu, dt_s, self.t_s)
        self._bodies.step(self._state, self._vu, dt_s)  # the space integrates the moves
        if self._movers:
            self._advance_routes(dt_s)
        self.t_s += dt_s

    def states(self) -> list[AgentState]:
        """Immutable snapshots of all agents in the street, in order of entry."""
        if not self._movers:
            return []
        out = []
        poses = self._state[:, : PHASE + 1].tolist()
        velocities = self._vu[VEL].tolist()
        for a, (x, y, th, phase), (vx, vy) in zip(self._movers, poses, velocities, strict=True):
            t = a.traits
            members = tuple(
                _member_state(m, p) for m, p in zip(t.members, a.member_phases, strict=True)
            ) if t.members else ()
            out.append(frozen_from_fields(AgentState, {
                "object_id": a.oid, "cls": t.cls, "x_m": x, "y_m": y,
                "heading_rad": (th + math.pi) % TWO_PI - math.pi, "speed_mps": math.hypot(vx, vy),
                "length_m": t.length_m, "width_m": t.width_m, "height_m": t.height_m,
                "gait_phase_rad": phase, "members": members, "light_on": t.light_on,
            }))  # fmt: skip
        return out

    def snapshot_rows(self) -> tuple[list[int], list[tuple[float, float, float, float, float]], list[float]]:
        """What of ``states()`` changes from step to step, without building the snapshots (the
        traffic recorder's rows): the agents' object ids in order of entry, their (x_m, y_m,
        heading_rad, speed_mps, gait_phase_rad), and their group members' gait phases in the same
        order; the same values as ``states()`` gives, computed by the same expressions."""
        if not self._movers:
            return [], [], []
        oids, rows, member_phases = [], [], []
        poses = self._state[:, : PHASE + 1].tolist()
        velocities = self._vu[VEL].tolist()
        for a, (x, y, th, phase), (vx, vy) in zip(self._movers, poses, velocities, strict=True):
            oids.append(a.oid)
            rows.append((x, y, (th + math.pi) % TWO_PI - math.pi, math.hypot(vx, vy), phase))
            if a.traits.members:
                member_phases.extend(a.member_phases)
        return oids, rows, member_phases

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
                n = len(self._state)
                xy, th = np.empty((n + 1, 2)), np.empty(n + 1)
                ln, wd = np.empty(n + 1), np.empty(n + 1)
                xy[0], th[0], ln[0], wd[0] = (x, y), heading, traits.length_m, traits.width_m
                xy[1:], th[1:] = self._state[:, X : X + 2], self._state[:, TH]
                ln[1:], wd[1:] = self._state[:, LENGTH], self._state[:, WIDTH]
                if oriented_overlaps(xy, th, ln, wd, margin_m=ENTRY_CLEARANCE_M)[0].any():
                    continue
                gap = self._gap_ahead(x, y, leg, traits)
                if gap < motion.min_gap_m:
                    continue
                speed = min(speed, max(0.0, (gap - motion.min_gap_m) / motion.headway_s))
            queue.popleft()
            if not queue:
                del self._pending[key]
            agent = Mover(oid, traits, route.legs)
            self._bodies.add((x, y, heading), traits.length_m, traits.width_m)
            row, vu = new_row(agent, (x, y, heading), speed)
            self._state = np.concatenate([self._state, row])
            self._vu = np.concatenate([self._vu, vu], axis=1)
            self._agents[oid] = agent
            self._movers.append(agent)
            self.spawned_count += 1

    def _gap_ahead(self, x: float, y: float, leg: Leg, traits: AgentTraits) -> float:
        """Free distance ahead of a footprint at (x, y) on ``leg``, within its corridor, m."""
        ux, uy = leg.unit
        best = math.inf
        for a, (ox, oy) in zip(self._movers, self._state[:, X : X + 2].tolist(), strict=True):
            f = (ox - x) * ux + (oy - y) * uy
            lat = -(ox - x) * uy + (oy - y) * ux
            reach = max(a.traits.length_m, a.traits.width_m) / 2
            if f > 0 and abs(lat) < reach + traits.width_m / 2 + 0.1:
                best = min(best, f - reach - traits.length_m / 2)
        return best

    # ------------------------------------------------------ after the move
    def _advance_routes(self, dt: float) -> None:
        """After the move: gait phases, leg changes, removal of leavers, pauses (animals)."""
        _, advance = _compiled()
        agents = self._movers
        speeds = [math.hypot(vx, vy) for vx, vy in self._vu[VEL].tolist()]
        leg_done = np.zeros(len(agents), dtype=bool)
        done = advance(self._state, self._vu, np.array(speeds), dt, self.t_s, leg_done)
        gone = self._next_legs(np.flatnonzero(leg_done).tolist()) if done else []
        for i, (a, speed) in enumerate(zip(agents, speeds, strict=True)):
            if a.member_phases:
                dist = speed * dt
                a.member_phases = [(p + TWO_PI * dist / a.traits.stride_m) % TWO_PI for p in a.member_phases]
            pauses = a.pauses  # animals stop now and then
            if pauses is not None and i not in gone and self._state[i, PAUSE] < self.t_s:
                if self.rng.random() < dt / pauses.every_s:
                    self._state[i, PAUSE] = self.t_s + float(self.rng.uniform(*pauses.duration_s))
        if gone:
            self._bodies.remove(gone)
            self._state = np.delete(self._state, gone, axis=0)
            self._vu = np.delete(self._vu, gone, axis=1)
            for i in gone:
                del self._agents[agents[i].oid]
            self._movers = [a for i, a in enumerate(agents) if i not in gone]
            self.removed_count += len(gone)

    def _next_legs(self, rows: list[int]) -> list[int]:
        """Move the agents of ``rows`` that reached their leg's end on to the next leg; the rows of
        those that finished their route."""
        gone = []
        for i in rows:
            a = self._movers[i]
            x, y = self._state[i, X : X + 2].tolist()
            while True:
                leg = a.leg
                ux, uy = leg.unit
                s = (x - leg.start_xy_m[0]) * ux + (y - leg.start_xy_m[1]) * uy
                if s < leg.length_m:
                    break
                if a.leg_i + 1 == len(a.legs):
                    gone.append(i)
                    break
                a.leg_i += 1
                self._state[i, TARGET] = a.leg.pref_m
            set_leg(self._state, self._vu, i, a)
        return gone

    # ------------------------------------------------------------- diagnostics
    def stuck_agents(self, min_still_s: float = 60.0) -> list[int]:
        """Ids of agents held still for ``min_still_s`` by others (not waiting at a kerb or
        pausing): a behaviour bug if ever non-empty."""
        still = self._state[:, STILL].tolist()
        return [a.oid for a, s in zip(self._movers, still, strict=True) if s >= min_still_s]

    def traits_of(self, object_id: int) -> AgentTraits:
        """How an agent in the street looks and how fast it wants to go."""
        return self._agents[object_id].traits

    def route_leg(self, object_id: int) -> Leg:
        """The leg an agent is on now (tests and debugging)."""
        return self._agents[object_id].leg


@functools.cache
def _compiled() -> tuple[Callable, Callable]:
    """The compiled step (``behaviour.move_agents``, ``moves_compiled.advance``), imported on the
    first step: it loads numba, which a process that only replays recorded traffic never needs."""
    from citysim.world.behaviour import move_agents
    from citysim.world.moves_compiled import advance

    return move_agents, advance


def _member_state(m: MemberState, phase: float) -> MemberState:
    """Group member ``m`` at gait phase ``phase`` (its other fields as drawn)."""
    return frozen_from_fields(MemberState, {
        "forward_m": m.forward_m, "left_m": m.left_m, "width_m": m.width_m, "height_m": m.height_m,
        "length_m": m.length_m, "gait_phase_rad": phase,
    })  # fmt: skip


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
