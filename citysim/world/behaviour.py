"""How agents decide their motion, each physics step, vectorised over all agents.

``plan_moves`` reads every agent's pose and route, decides its next move and
hands it to its pymunk body as a velocity and angular velocity:

* longitudinal: the Intelligent Driver Model (Treiber, Hennecke & Helbing
  2000) toward the desired speed, with the nearest agent ahead in the corridor
  as leader (vehicles follow vehicles, brake for crossing pedestrians and
  animals; walkers slow behind walkers), plus a hard clamp that never moves an
  agent into its leader (half the gap for an oncoming one);
* lateral: the offset within the leg's band that maximises the free distance
  coverable within ``horizon_s``, minus reluctance to leave the preferred side
  or the comfort band (``choose_offsets``): walkers keep right and step aside,
  cars swing out around cyclists, runners overtake; facing someone oncoming,
  both step to the band's edge; the held-up grow impatient;
* giving way: a walker about to cross the road waits at the kerb while a
  vehicle or cyclist would reach the crossing before the walker has left its
  strip of road (``must_wait``);
* last resort: proposed poses are checked pairwise as oriented boxes and a
  move that would overlap is cut back (its turn, its sidestep, all of it)
  (``resolve_overlaps``), so no two footprints ever overlap.

Conventions: world frame of DESIGN.md; offsets are metres to the left of the
leg direction (``citysim.world.geometry``); speeds m/s; angles rad CCW from +x.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
import pymunk

from citysim.config.kinds import AGENT_KINDS
from citysim.world.agents import AgentTraits
from citysim.world.conflicts import must_wait, resolve_overlaps
from citysim.world.geometry import Leg, wrap_angle

#: Lateral candidates evaluated per agent and step (evenly over the band).
N_LATERAL_CANDIDATES = 9
#: Score weights, metres of free distance per metre of offset: away from the
#: preferred side, outside the comfort band, and away from the last choice.
W_PREF, W_COMFORT, W_KEEP = 0.3, 1.5, 0.2
#: Impatience: an agent held still for t seconds weighs those reluctances by
#: 1 / (1 + t / IMPATIENCE_S), so two that block each other soon both give way.
IMPATIENCE_S = 2.0
#: Clearance the behaviour keeps between footprints (sidestepping, closing up), m.
CLEARANCE_M = 0.01


class Mover:
    """One agent's mutable state: its body, route progress, speed and gait (snapshots go out as AgentState)."""

    __slots__ = (
        "oid", "traits", "body", "shape", "legs", "leg_i", "target_m",
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
        self.still_s = 0.0  # seconds held still by others (not waiting at a kerb, not pausing)
        self.waiting = False
        self.road_user = AGENT_KINDS[traits.cls].road_user  # walkers give way to it

    @property
    def leg(self) -> Leg:
        return self.legs[self.leg_i]


class Layout:
    """Arrays of per-agent constants, in agent order, for one set of (agent, leg) pairs."""

    def __init__(self, key: tuple, agents: list[Mover]) -> None:
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


def layout_for(agents: list[Mover], cached: Layout | None) -> Layout:
    """The cached layout if the same agents are on the same legs, else a new one."""
    key = tuple((a.oid, a.leg_i) for a in agents)
    return cached if cached is not None and cached.key == key else Layout(key, agents)


@dataclass(frozen=True)
class Surroundings:
    """Every pair of agents seen from each one's leg frame (arrays [i, j]: j as agent i sees it).

    ``fwd``/``lat``: j's position along / across i's leg (lat from i's leg line); ``ext_f``/
    ``ext_l``: j's half extents along / across i's leg; ``gap``: free distance from i's front to
    j's back along i's leg; ``v_along``: j's velocity along i's leg; ``ahead``: j in front of i
    within its look-ahead; ``beside``: j level with i; ``half``: i's half width plus its margin
    (less when impatient). Metres, m/s and radians; ``d`` is pos_j - pos_i in the world frame.
    """

    d: np.ndarray
    lat: np.ndarray
    phi: np.ndarray
    ext_l: np.ndarray
    self_l: np.ndarray
    gap: np.ndarray
    v_along: np.ndarray
    ahead: np.ndarray
    beside: np.ndarray
    half: np.ndarray


@dataclass(frozen=True)
class LateralWish:
    """Per agent: where it stands across its leg now (``off``), where it aimed before and prefers
    to be, its band and comfort band, patience, desired speed and look-ahead time."""

    off: np.ndarray
    target_prev: np.ndarray
    pref: np.ndarray
    band: np.ndarray
    comfort: np.ndarray
    patience: np.ndarray
    v0: np.ndarray
    horizon: np.ndarray

    def rows(self, rows: np.ndarray) -> LateralWish:
        return LateralWish(*(getattr(self, f.name)[rows] for f in fields(self)))


def surroundings(lay: Layout, pos: np.ndarray, th: np.ndarray, vel: np.ndarray, off: np.ndarray,
                 patience: np.ndarray) -> Surroundings:  # fmt: skip
    """Each agent's view of every other in its own leg frame (see ``Surroundings``)."""
    n = len(pos)
    length, width, unit, normal = lay.length, lay.width, lay.unit, lay.normal
    look, margin = lay.motion[5], lay.motion[7]
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
    half = self_l + margin * patience  # the held-up squeeze past with less clearance
    beside = others & (np.abs(fwd) < ext_f + self_f[:, None] + 0.3)
    return Surroundings(d, lat, phi, ext_l, self_l, gap, v_along, ahead, beside, half)


def plan_moves(agents: list[Mover], lay: Layout, dt: float, t_s: float) -> int:
    """Decide every agent's move for the next ``dt`` seconds and hand it to its pymunk body.

    Sets each body's velocity and angular velocity (``Space.step`` then integrates
    them) and each agent's speed, lateral target and waiting flag. Returns the
    number of moves the last-resort overlap check dropped.
    """
    pos = np.array([tuple(a.body.position) for a in agents])
    th = np.array([a.body.angle for a in agents])
    vel = np.array([a.velocity for a in agents])
    dyn = np.array([(a.speed_mps, a.target_m, a.still_s, a.pause_until_s) for a in agents])
    patience = 1.0 / (1.0 + dyn[:, 2] / IMPATIENCE_S)
    v0 = np.where(dyn[:, 3] > t_s, 0.0, lay.v0)  # a pausing animal wants to stand
    rel = pos - lay.start
    s_along = np.einsum("ik,ik->i", rel, lay.unit)
    off = np.einsum("ik,ik->i", rel, lay.normal)
    nb = surroundings(lay, pos, th, vel, off, patience)
    wish = LateralWish(off, dyn[:, 1], lay.pref, lay.band, lay.comfort, patience, v0, lay.motion[8])

    # ---- lateral choice (only agents with someone ahead or beside; the rest head for pref)
    target = lay.pref.copy()
    reachable = (nb.lat + nb.ext_l > (lay.band[:, 0] - nb.half)[:, None]) & (
        nb.lat - nb.ext_l < (lay.band[:, 1] + nb.half)[:, None]
    )
    rows = np.flatnonzero((nb.ahead & reachable | nb.beside).any(axis=1))
    if rows.size:
        target[rows] = choose_offsets(rows, wish, nb, lay.unit)

    # ---- giving way at the kerb
    wait_here, wait_at_end = must_wait(agents, pos, vel, lay.length, lay.width, s_along, lay.leg_len)
    target = np.where(wait_here, off, target)
    step_lat = lateral_step(lay, nb, off, target, dt)
    ds = forward_step(lay, nb, dyn[:, 0], v0, off, step_lat, dt)
    # a walker that must give way stops at the kerb (end of its leg, or start of the crossing)
    to_end = lay.leg_len - s_along
    ds = np.where(wait_at_end, np.minimum(ds, np.maximum(to_end - 0.01, 0.0) * (to_end > 0.05)), ds)
    ds = np.where(wait_here, 0.0, ds)
    return move_bodies(agents, lay, (pos, th), (ds, step_lat, v0), (target, wait_here | wait_at_end), dt)


def lateral_step(lay: Layout, nb: Surroundings, off: np.ndarray, target: np.ndarray, dt: float) -> np.ndarray:
    """Each agent's sideways step toward its target this step, stopping short of anyone beside, m."""
    v_lat = lay.motion[6]
    step_lat = np.clip(target - off, -v_lat * dt, v_lat * dt)
    lat, ext_l, self_l, beside = nb.lat, nb.ext_l, nb.self_l, nb.beside
    room_left = np.where(
        beside & (lat > off[:, None]), lat - ext_l - (off + self_l)[:, None], np.inf
    ).min(1)
    room_right = np.where(
        beside & (lat < off[:, None]), (off - self_l)[:, None] - (lat + ext_l), np.inf
    ).min(1)
    # the one beside may step toward me in the same step: each takes half the room
    room_left, room_right = (room_left - CLEARANCE_M) / 2, (room_right - CLEARANCE_M) / 2
    return np.clip(step_lat, -np.maximum(room_right, 0), np.maximum(room_left, 0))


def forward_step(lay: Layout, nb: Surroundings, speed: np.ndarray, v0: np.ndarray, off: np.ndarray,
                 step_lat: np.ndarray, dt: float) -> np.ndarray:  # fmt: skip
    """Each agent's step along its leg: the Intelligent Driver Model behind the leader in the
    corridor its sideways step sweeps, never more than the room left to that leader, m."""
    n = len(off)
    acc_max, b_comf, b_max, headway, s0 = lay.motion[:5]
    off_new = off + step_lat
    c_lo = np.minimum(off, off_new) - nb.half
    c_hi = np.maximum(off, off_new) + nb.half
    in_corridor = nb.ahead & (nb.lat + nb.ext_l > c_lo[:, None]) & (nb.lat - nb.ext_l < c_hi[:, None])
    lead_gap = np.where(in_corridor, nb.gap, np.inf)
    lead = np.argmin(lead_gap, axis=1)
    g = lead_gap[np.arange(n), lead]
    has_lead = np.isfinite(g)
    v_lead = np.where(has_lead, nb.v_along[np.arange(n), lead], 0.0)
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
    return np.where(has_lead, np.minimum(ds, np.maximum(room, 0.0)), ds)


def move_bodies(agents: list[Mover], lay: Layout, pose: tuple, step: tuple, intent: tuple, dt: float) -> int:
    """Hand the moves to the pymunk bodies, dropping those that would overlap; the count dropped.

    ``pose`` = (positions, headings) now; ``step`` = (along, sideways, desired speed);
    ``intent`` = (lateral targets, waiting flags)."""
    (pos, th), (ds, step_lat, v0), (target, waiting) = pose, step, intent
    yaw_rate, max_tilt = lay.motion[9], lay.motion[10]
    new_pos = pos + ds[:, None] * lay.unit + step_lat[:, None] * lay.normal
    # face along the leg; riders and drivers tilt into a swerve (a slow one does
    # not turn on the spot), walkers and animals sidestep facing forward, which
    # also keeps side-by-side footprints parallel
    tilt = np.clip(np.arctan2(step_lat, np.maximum(ds, v0 * dt)), -max_tilt, max_tilt)
    want = lay.heading + tilt
    new_th = th + np.clip(wrap_angle(want - th), -yaw_rate * dt, yaw_rate * dt)
    along_pos = pos + ds[:, None] * lay.unit
    new_pos, new_th, stage = resolve_overlaps(pos, th, new_pos, new_th, along_pos, lay.length, lay.width)
    ds = np.where(stage < 3, ds, 0.0)

    velocity = ((new_pos - pos) / dt).tolist()
    omega = (wrap_angle(new_th - th) / dt).tolist()
    rows = zip(agents, velocity, omega, (ds / dt).tolist(), target.tolist(), waiting.tolist(), strict=True)
    for a, vel_i, omega_i, speed_i, target_i, waiting_i in rows:
        a.body.velocity = a.velocity = tuple(vel_i)
        a.body.angular_velocity = omega_i
        a.speed_mps, a.target_m, a.waiting = speed_i, target_i, waiting_i
    return int((stage == 3).sum())


def choose_offsets(rows: np.ndarray, wish: LateralWish, nb: Surroundings, unit: np.ndarray) -> np.ndarray:
    """Best lateral offset for agents ``rows``: the candidate with the most free distance
    within ``horizon`` (minus reluctance), among those reachable without sweeping into
    anyone beside."""
    me = wish.rows(rows)
    off, target_prev, pref, band, comfort = me.off, me.target_prev, me.pref, me.band, me.comfort
    v0, horizon, half, patience = me.v0, me.horizon, nb.half[rows], me.patience
    lat, ext_l, gap, v_along, phi = nb.lat[rows], nb.ext_l[rows], nb.gap[rows], nb.v_along[rows], nb.phi[rows]
    ahead, beside, d = nb.ahead[rows], nb.beside[rows], nb.d
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
    facing = ahead & in_lane[:, 0, :] & (np.cos(phi) < -0.5) & (gap < (v0 * horizon)[:, None] + 2.0)
    face = np.flatnonzero(facing.any(axis=1))
    if face.size:
        nearest = np.argmin(np.where(facing[face], gap[face], np.inf), axis=1)
        # which side the other is on, in a frame both share (axis: my direction minus
        # theirs), so the two always pick opposite ways even on skew paths
        me = rows[face]
        axis = unit[me] - unit[nearest]
        rel = d[me, nearest]
        on_left = rel[:, 1] * axis[:, 0] - rel[:, 0] * axis[:, 1] >= 0
        edge = np.where(on_left, band[face, 0], band[face, 1])
        score[face] = -np.abs(cands[face] - edge[:, None])
    score[infeasible] = -np.inf  # never column 0: staying at the current offset sweeps nothing
    return cands[np.arange(len(rows)), np.argmax(score, axis=1)]
