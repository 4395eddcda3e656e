"""The moving world: agents as pymunk bodies following their routes without overlapping.

Every agent is a *kinematic* pymunk body carrying a box shape (its ground
footprint). Kinematic, not dynamic, because the motion is prescribed by the
behaviour model below (path following, car following, giving way): a
kinematic body follows the velocity it is given exactly, is never shoved off
its sidewalk or lane by a contact impulse, and costs the solver nothing
(Chipmunk does not collide kinematic bodies with each other). Dynamic bodies
would resolve contacts only after they overlap, with some penetration slop;
here overlaps are prevented before they happen. Each step the world sets every
body's velocity and angular velocity and ``Space.step`` integrates the poses.

Behaviour, per agent and step (vectorised over all agents):

* longitudinal: the Intelligent Driver Model toward the agent's desired speed,
  with the nearest agent ahead in its corridor as leader (vehicles follow
  vehicles, brake for crossing pedestrians and animals; walkers slow behind
  walkers), plus a hard clamp that never moves it into the leader;
* lateral: the agent picks an offset within its path's band that maximises
  the free distance it can cover in ``horizon_s`` (minus reluctance to leave
  its comfort band or preferred side): walkers keep right and step aside for
  oncoming ones, cars swing out around cyclists, runners overtake;
* giving way: a walker about to cross the road waits at the kerb until no
  vehicle or cyclist would reach its crossing before it is over;
* last resort: proposed poses are checked pairwise (oriented boxes); a move
  that would overlap is dropped (first the turn, then the whole move), so no
  two footprints ever overlap.

Agents leave at the street ends (or at the end of their route) and are removed
from the space; memory stays flat. Same street, same spawns, same rng -> the
same trajectories, bit for bit.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Generator
from dataclasses import replace

import numpy as np
import pymunk

from citysim.agents import AGENT_KINDS, AgentKind, AgentState, AgentTraits, MotionParams
from citysim.street import Street
from citysim.world_geometry import Leg, Route, oriented_overlaps, wrap_angle

__all__ = ["Leg", "Route", "World", "physics_process"]

#: Lateral candidates evaluated per agent and step (evenly over the band).
N_LATERAL_CANDIDATES = 9
#: Score weights, metres of free distance per metre of offset: away from the
#: preferred side, outside the comfort band, and away from the last choice.
W_PREF, W_COMFORT, W_KEEP = 0.3, 1.5, 0.2
#: Impatience: an agent held still for t seconds weighs those reluctances by
#: 1 / (1 + t / IMPATIENCE_S), so two that block each other soon both give way.
IMPATIENCE_S = 2.0
#: Road users walkers give way to before stepping onto the road.
ROAD_USERS = ("vehicle", "cyclist")
#: Extra time a crossing walker wants between the crossing and the next road user, s.
CROSSING_MARGIN_S = 1.5
#: Clearance the behaviour keeps between footprints (sidestepping, closing up), m.
CLEARANCE_M = 0.01
#: Overlap the last-resort check tolerates: pymunk integrates p + v dt, which may
#: land a float rounding (~1e-14 m) away from the checked pose.
OVERLAP_TOLERANCE_M = 1e-9


class _Agent:
    """Mutable per-agent state (the world's own; snapshots go out as AgentState)."""

    __slots__ = (
        "oid", "traits", "kind", "motion", "body", "shape", "legs", "leg_i", "target_m",
        "speed_mps", "velocity", "phase", "member_phases", "pause_until_s", "still_s", "road_user", "waiting",
    )  # fmt: skip

    def __init__(
        self,
        oid: int,
        traits: AgentTraits,
        legs: tuple[Leg, ...],
        body: pymunk.Body,
        shape: pymunk.Poly,
    ):
        self.oid = oid
        self.traits = traits
        self.kind: AgentKind = AGENT_KINDS[traits.cls]
        self.motion: MotionParams = self.kind.motion
        self.body = body
        self.shape = shape
        self.legs = legs
        self.leg_i = 0
        self.target_m = legs[0].pref_m
        self.speed_mps = 0.0
        self.velocity = (0.0, 0.0)
        self.phase = traits.gait_phase_rad
        self.member_phases = [m.gait_phase_rad for m in traits.members]
        self.pause_until_s = -1.0
        self.still_s = 0.0  # seconds held still, waiting at the kerb or pausing aside
        self.waiting = False
        self.road_user = traits.cls in ROAD_USERS

    @property
    def leg(self) -> Leg:
        return self.legs[self.leg_i]


class _Layout:
    """Arrays of per-agent constants, in agent order, for one set of (agent, leg) pairs."""

    def __init__(self, key: tuple, agents: list[_Agent]) -> None:
        self.key = key
        legs = [a.leg for a in agents]
        self.length = np.array([a.traits.length_m for a in agents])
        self.width = np.array([a.traits.width_m for a in agents])
        self.v0 = np.array([a.traits.desired_speed_mps for a in agents])
        self.unit = np.array([leg.unit for leg in legs])
        self.normal = np.stack([-self.unit[:, 1], self.unit[:, 0]], axis=1)
        self.heading = np.arctan2(self.unit[:, 1], self.unit[:, 0])
        self.start = np.array([leg.start_xy_m for leg in legs])
        self.leg_len = np.array([leg.length_m for leg in legs])
        self.band = np.array([leg.band_m for leg in legs])
        self.comfort = np.array([leg.comfort_m for leg in legs])
        self.pref = np.array([leg.pref_m for leg in legs])
        self.motion = np.array([_MOTION_ROWS[a.traits.cls] for a in agents]).T


_MOTION_FIELDS = (
    "accel_mps2", "comfort_decel_mps2", "max_decel_mps2", "headway_s", "min_gap_m", "lookahead_m",
    "lateral_speed_mps", "lateral_margin_m", "horizon_s", "yaw_rate_rps", "max_tilt_rad",
)  # fmt: skip
_MOTION_ROWS = {
    cls: tuple(getattr(k.motion, f) for f in _MOTION_FIELDS) for cls, k in AGENT_KINDS.items()
}


class World:
    """Agents on a street. ``rng`` drives in-world choices (animals stopping to sniff)."""

    def __init__(self, street: Street, rng: np.random.Generator) -> None:
        self.street = street
        self.rng = rng
        self.space = pymunk.Space()
        self.t_s = 0.0
        self._agents: dict[int, _Agent] = {}
        self._pending: dict[str, deque[tuple[int, AgentTraits, Route]]] = {}
        self._next_id = 0
        self.spawned_count = 0
        self.removed_count = 0
        self.blocked_moves = 0  # moves dropped by the last-resort overlap check (diagnostic)
        self._layout_cache: _Layout | None = None

    @classmethod
    def from_scenario(cls, scenario, rng: np.random.Generator) -> World:
        from citysim.street import build_street

        return cls(build_street(scenario), rng)

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
            self._move(agents, dt_s)
        self.space.step(dt_s)
        if agents:
            self._advance_routes(agents, dt_s)
        self.t_s += dt_s

    def states(self) -> list[AgentState]:
        """Immutable snapshots of all agents in the street, in id order."""
        out = []
        for a in self._agents.values():
            x, y = a.body.position
            members = tuple(
                replace(m, gait_phase_rad=p)
                for m, p in zip(a.traits.members, a.member_phases, strict=True)
            )
            out.append(
                AgentState(
                    object_id=a.oid,
                    cls=a.traits.cls,
                    x_m=float(x),
                    y_m=float(y),
                    heading_rad=float(a.body.angle),
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
                if oriented_overlaps(xy, th, ln, wd, margin_m=motion.min_gap_m / 2)[0].any():
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
            agent = _Agent(oid, traits, route.legs, body, shape)
            agent.speed_mps = speed
            self._agents[oid] = agent
            self.spawned_count += 1

    @staticmethod
    def _gap_ahead(
        x: float, y: float, leg: Leg, traits: AgentTraits, others: list[_Agent]
    ) -> float:
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

    # -------------------------------------------------------------------- move
    def _layout(self, agents: list[_Agent]) -> _Layout:
        """Per-agent constants (sizes, legs, motion parameters); rebuilt when agents or legs change."""
        key = tuple((a.oid, a.leg_i) for a in agents)
        if self._layout_cache is None or self._layout_cache.key != key:
            self._layout_cache = _Layout(key, agents)
        return self._layout_cache

    def _move(self, agents: list[_Agent], dt: float) -> None:
        n = len(agents)
        lay = self._layout(agents)
        length, width, unit, normal, start = lay.length, lay.width, lay.unit, lay.normal, lay.start
        leg_len, band, comfort, pref = lay.leg_len, lay.band, lay.comfort, lay.pref
        acc_max, b_comf, b_max, headway, s0, look, v_lat, margin, horizon, yaw_rate, max_tilt = (
            lay.motion
        )
        pos = np.array([tuple(a.body.position) for a in agents])
        th = np.array([a.body.angle for a in agents])
        vel = np.array([a.velocity for a in agents])
        dyn = np.array([(a.speed_mps, a.target_m, a.still_s, a.pause_until_s) for a in agents])
        speed, target_prev = dyn[:, 0], dyn[:, 1]
        patience = 1.0 / (1.0 + dyn[:, 2] / IMPATIENCE_S)
        v0 = np.where(dyn[:, 3] > self.t_s, 0.0, lay.v0)  # a pausing animal wants to stand

        rel = pos - start
        s_along = np.einsum("ik,ik->i", rel, unit)
        off = np.einsum("ik,ik->i", rel, normal)

        # ---- pairwise geometry in each agent's leg frame: d[i, j] = pos_j - pos_i
        d = pos[None, :, :] - pos[:, None, :]
        fwd = np.einsum("ijk,ik->ij", d, unit)
        lat = off[:, None] + np.einsum("ijk,ik->ij", d, normal)
        phi = th[None, :] - lay.heading[:, None]
        cphi, sphi = np.abs(np.cos(phi)), np.abs(np.sin(phi))
        ext_f = length[None, :] / 2 * cphi + width[None, :] / 2 * sphi
        ext_l = length[None, :] / 2 * sphi + width[None, :] / 2 * cphi
        self_f, self_l = np.diag(ext_f).copy(), np.diag(ext_l).copy()
        v_along = vel @ unit.T  # v_along[j, i] = vel_j . unit_i
        v_along = v_along.T
        others = ~np.eye(n, dtype=bool)
        gap = fwd - ext_f - self_f[:, None]
        ahead = others & (fwd > 0) & (gap < look[:, None])
        half = self_l + margin
        beside = others & (np.abs(fwd) < ext_f + self_f[:, None] + 0.3)

        # ---- lateral choice (only agents with someone ahead or beside; the rest head for pref)
        target = pref.copy()
        reachable = (lat + ext_l > (band[:, 0] - half)[:, None]) & (
            lat - ext_l < (band[:, 1] + half)[:, None]
        )
        rows = np.flatnonzero((ahead & reachable | beside).any(axis=1))
        if rows.size:
            target[rows] = self._choose_offsets(
                rows, off, target_prev, pref, band, comfort, patience, v0, horizon, half,
                lat, ext_l, gap, v_along, phi, ahead, beside,
            )  # fmt: skip

        # ---- giving way at the kerb
        wait_here, wait_at_end = self._must_wait(agents, pos, vel, length, width, s_along, leg_len)
        target = np.where(wait_here, off, target)

        # ---- lateral step, stopping short of anyone beside
        step_lat = np.clip(target - off, -v_lat * dt, v_lat * dt)
        room_left = np.where(
            beside & (lat > off[:, None]), lat - ext_l - (off + self_l)[:, None], np.inf
        ).min(1)
        room_right = np.where(
            beside & (lat < off[:, None]), (off - self_l)[:, None] - (lat + ext_l), np.inf
        ).min(1)
        room_left, room_right = room_left - CLEARANCE_M, room_right - CLEARANCE_M
        step_lat = np.clip(step_lat, -np.maximum(room_right, 0), np.maximum(room_left, 0))
        off_new = off + step_lat

        # ---- longitudinal: IDM behind the leader in the swept corridor
        c_lo = np.minimum(off, off_new) - half
        c_hi = np.maximum(off, off_new) + half
        in_corridor = ahead & (lat + ext_l > c_lo[:, None]) & (lat - ext_l < c_hi[:, None])
        lead_gap = np.where(in_corridor, gap, np.inf)
        lead = np.argmin(lead_gap, axis=1)
        g = lead_gap[np.arange(n), lead]
        has_lead = np.isfinite(g)
        v_lead = np.where(has_lead, v_along[np.arange(n), lead], 0.0)
        v = np.maximum(speed, 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            free_term = np.where(v0 > 0, 1.0 - (v / np.maximum(v0, 1e-9)) ** 4, -1.0)
            s_star = s0 + np.maximum(
                0.0, v * headway + v * (v - v_lead) / (2.0 * np.sqrt(acc_max * b_comf))
            )
            inter = np.where(has_lead, (s_star / np.maximum(g, 0.01)) ** 2, 0.0)
        acc = np.clip(acc_max * (free_term - inter), -b_max, acc_max)
        v_new = np.clip(v + acc * dt, 0.0, v0)
        # never exceed the desired speed in total (forward and sideways together)
        v_new = np.minimum(v_new, np.sqrt(np.maximum(v0**2 - (step_lat / dt) ** 2, 0.0)))
        ds = v_new * dt
        oncoming = has_lead & (v_lead < -0.05)
        room = np.where(oncoming, g / 2, g) - CLEARANCE_M
        ds = np.where(has_lead, np.minimum(ds, np.maximum(room, 0.0)), ds)
        # a walker that must give way stops at the kerb (end of its leg, or start of the crossing)
        to_end = leg_len - s_along
        ds = np.where(
            wait_at_end, np.minimum(ds, np.maximum(to_end - 0.01, 0.0) * (to_end > 0.05)), ds
        )
        ds = np.where(wait_here, 0.0, ds)

        # ---- proposed poses; drop moves that would overlap
        new_pos = pos + ds[:, None] * unit + step_lat[:, None] * normal
        # face along the leg; riders and drivers tilt into a swerve (a slow one does
        # not turn on the spot), walkers and animals sidestep facing forward, which
        # also keeps side-by-side footprints parallel
        tilt = np.clip(np.arctan2(step_lat, np.maximum(ds, v0 * dt)), -max_tilt, max_tilt)
        want = lay.heading + tilt
        new_th = th + np.clip(wrap_angle(want - th), -yaw_rate * dt, yaw_rate * dt)
        new_pos, new_th, kept = self._resolve(pos, th, new_pos, new_th, length, width)
        ds = np.where(kept, ds, 0.0)
        self.blocked_moves += int((~kept).sum())

        for i, a in enumerate(agents):
            vx, vy = (new_pos[i] - pos[i]) / dt
            a.body.velocity = (float(vx), float(vy))
            a.body.angular_velocity = float(wrap_angle(new_th[i] - th[i])) / dt
            a.velocity = (float(vx), float(vy))
            a.speed_mps = float(ds[i] / dt)
            a.target_m = float(target[i])
            a.waiting = bool(wait_here[i] or wait_at_end[i])

    @staticmethod
    def _choose_offsets(
        rows, off, target_prev, pref, band, comfort, patience, v0, horizon, half,
        lat, ext_l, gap, v_along, phi, ahead, beside,
    ) -> np.ndarray:  # fmt: skip
        """Best lateral offset for agents ``rows``: the candidate with the most free distance
        within ``horizon`` (minus reluctance), among those reachable without sweeping into
        anyone beside."""
        off, target_prev, pref, band, comfort = (
            off[rows],
            target_prev[rows],
            pref[rows],
            band[rows],
            comfort[rows],
        )
        v0, horizon, half, patience = v0[rows], horizon[rows], half[rows], patience[rows]
        lat, ext_l, gap, v_along, phi = lat[rows], ext_l[rows], gap[rows], v_along[rows], phi[rows]
        ahead, beside = ahead[rows], beside[rows]
        cands = np.concatenate(
            [off[:, None], target_prev[:, None], pref[:, None],
             np.linspace(band[:, 0], band[:, 1], N_LATERAL_CANDIDATES, axis=1)],
            axis=1,
        )  # fmt: skip
        cands[:, 1:] = np.clip(cands[:, 1:], band[:, :1], band[:, 1:])
        lat3, ext3 = lat[:, None, :], ext_l[:, None, :]
        in_lane = np.abs(lat3 - cands[:, :, None]) < ext3 + half[:, None, None]
        reach = gap[:, None, :] + v_along[:, None, :] * horizon[:, None, None]
        blocked = ahead[:, None, :] & in_lane
        free = np.minimum(np.where(blocked, reach, np.inf).min(axis=2), (v0 * horizon)[:, None])
        sweep_lo = np.minimum(off[:, None], cands) - half[:, None]
        sweep_hi = np.maximum(off[:, None], cands) + half[:, None]
        touch_now = (lat + ext_l > (off - half)[:, None]) & (lat - ext_l < (off + half)[:, None])
        touch = (lat3 + ext3 > sweep_lo[:, :, None]) & (lat3 - ext3 < sweep_hi[:, :, None])
        infeasible = (beside[:, None, :] & touch & ~touch_now[:, None, :]).any(axis=2)
        reluctance = (
            W_PREF * np.abs(cands - pref[:, None])
            + W_COMFORT
            * (np.maximum(0, comfort[:, :1] - cands) + np.maximum(0, cands - comfort[:, 1:]))
            + W_KEEP * np.abs(cands - target_prev[:, None])
        )
        score = free - patience[:, None] * reluctance
        # Facing someone oncoming in my way, step as far aside as the band allows,
        # to my right if they are on my left or dead ahead, else to my left: both
        # parties do, which clears the way whenever two can pass at all (each
        # alone would see no gain in a part-way sidestep, and both would wait).
        facing = (
            ahead & in_lane[:, 0, :] & (np.cos(phi) < -0.5) & (gap < (v0 * horizon)[:, None] + 2.0)
        )
        face = np.flatnonzero(facing.any(axis=1))
        if face.size:
            nearest = np.argmin(np.where(facing[face], gap[face], np.inf), axis=1)
            edge = np.where(lat[face, nearest] >= off[face], band[face, 0], band[face, 1])
            score[face] = -np.abs(cands[face] - edge[:, None])
        score[infeasible] = -np.inf  # never column 0: staying at the current offset sweeps nothing
        return cands[np.arange(len(rows)), np.argmax(score, axis=1)]

    def _must_wait(
        self, agents, pos, vel, length, width, s_along, leg_len
    ) -> tuple[np.ndarray, np.ndarray]:
        """Walkers that must give way: (at the start of their crossing, at the end of the leg before it).

        A walker crosses when every vehicle and cyclist heading for the crossing
        arrives only after the walker has left that road user's strip of road
        (plus ``CROSSING_MARGIN_S``): the near lane may be crossed in a gap the
        far lane would not give.
        """
        here = np.zeros(len(agents), dtype=bool)
        at_end = np.zeros(len(agents), dtype=bool)
        road = np.array([a.road_user for a in agents])
        if not road.any():
            return here, at_end
        r_xy, r_vel = pos[road], vel[road]
        r_dir = np.sign(np.array([a.leg.unit[0] for a in agents])[road])
        r_len, r_width = length[road], width[road]
        r_speed = np.hypot(r_vel[:, 0], r_vel[:, 1])
        for i, a in enumerate(agents):
            if a.road_user:
                continue
            if a.leg.yield_to_traffic and s_along[i] < 0.3:
                crossing, flag = a.leg, here
            elif (
                a.leg_i + 1 < len(a.legs)
                and a.legs[a.leg_i + 1].yield_to_traffic
                and leg_len[i] - s_along[i] < 3.0
            ):
                crossing, flag = a.legs[a.leg_i + 1], at_end
            else:
                continue
            pad = a.traits.width_m / 2 + 0.5
            x_lo = min(crossing.start_xy_m[0], crossing.end_xy_m[0]) - pad
            x_hi = max(crossing.start_xy_m[0], crossing.end_xy_m[0]) + pad
            front = r_xy[:, 0] + r_dir * r_len / 2
            rear = r_xy[:, 0] - r_dir * r_len / 2
            past = np.where(r_dir > 0, rear > x_hi, rear < x_lo)
            dist = np.where(r_dir > 0, x_lo - front, front - x_hi)
            t_arrive = np.maximum(dist, 0.0) / np.maximum(r_speed, 0.1)
            # walking distance until this walker has cleared each road user's strip
            y0, dy = crossing.start_xy_m[1], crossing.end_xy_m[1] - crossing.start_xy_m[1]
            cleared_m = (
                (np.abs(r_xy[:, 1] - y0) + (r_width + a.traits.width_m) / 2)
                * crossing.length_m
                / abs(dy)
            )
            t_leave = cleared_m / max(a.traits.desired_speed_mps, 0.5) + CROSSING_MARGIN_S
            flag[i] = bool(np.any(~past & (t_arrive < t_leave)))
        return here, at_end

    @staticmethod
    def _resolve(pos, th, new_pos, new_th, length, width):
        """Drop overlapping moves: first the turn, then the whole move, until no moved pair overlaps."""
        n = len(pos)
        moved = np.ones(n, dtype=bool)
        reach = np.hypot(length, width) / 2
        d = new_pos[None, :, :] - new_pos[:, None, :]
        near = np.hypot(d[..., 0], d[..., 1]) < reach[:, None] + reach[None, :]
        np.fill_diagonal(near, False)
        if not near.any():  # bounding circles apart: nothing can overlap
            return new_pos, new_th, moved
        turn_dropped = np.zeros(n, dtype=bool)
        new_pos, new_th = new_pos.copy(), new_th.copy()
        for _ in range(2 * n + 1):
            hit = oriented_overlaps(new_pos, new_th, length, width, margin_m=-OVERLAP_TOLERANCE_M)
            hit &= moved[:, None] | moved[None, :]
            culprit = hit.any(axis=1) & moved
            if not culprit.any():
                break
            first = culprit & ~turn_dropped
            second = culprit & turn_dropped
            new_th[first] = th[first]
            turn_dropped |= first
            new_pos[second], new_th[second] = pos[second], th[second]
            moved &= ~second
        return new_pos, new_th, moved

    # ----------------------------------------------------------------- routes
    def _advance_routes(self, agents: list[_Agent], dt: float) -> None:
        """After the space stepped: gait phases, leg changes, removal of leavers, animal pauses."""
        for a in agents:
            speed = math.hypot(*a.velocity)
            dist = speed * dt
            a.phase = (a.phase + 2.0 * math.pi * dist / a.traits.stride_m) % (2.0 * math.pi)
            if a.member_phases:
                a.member_phases = [
                    (p + 2.0 * math.pi * dist / a.traits.stride_m) % (2.0 * math.pi)
                    for p in a.member_phases
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
            if a.oid in self._agents and a.traits.cls == "animal" and a.pause_until_s < self.t_s:
                # foxes and dogs stop now and then (every ~10 s of walking, for 1-4 s)
                if self.rng.random() < dt / 10.0:
                    a.pause_until_s = self.t_s + float(self.rng.uniform(1.0, 4.0))

    def _remove(self, a: _Agent) -> None:
        self.space.remove(a.shape, a.body)
        del self._agents[a.oid]
        self.removed_count += 1

    # ------------------------------------------------------------- diagnostics
    def stuck_agents(self, min_still_s: float = 60.0) -> list[int]:
        """Ids of agents held still for ``min_still_s`` by others (not waiting at a kerb or
        pausing): a behaviour bug if ever non-empty."""
        return [a.oid for a in self._agents.values() if a.still_s >= min_still_s]

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
