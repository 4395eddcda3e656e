"""The behaviour model as numpy stated it before it was compiled: the oracle the compiled step is
checked against, bit for bit (``test_compiled.py``).

Kept as it ran (``citysim.world.behaviour`` and ``conflicts`` at the commit before the compiled
step), but for its two ends: it reads the world's arrays instead of pymunk bodies, and hands the
moves to pymunk kinematic bodies one by one (property by property, as the world once did).

Conventions: world frame, metres, seconds, m/s; angles rad CCW from +x; offsets metres to the
left of the leg direction.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
import pymunk

from citysim.config.kinds import AGENT_KINDS

# the rules' parameters are the compiled step's own: the oracle states the same rules with them
from citysim.world.behaviour_compiled import (
    CLEARANCE_M,
    IMPATIENCE_S,
    N_LATERAL_CANDIDATES,
    W_COMFORT,
    W_KEEP,
    W_PREF,
)
from citysim.world.conflicts import resolve_overlaps
from citysim.world.conflicts_compiled import CROSSING_MARGIN_S
from citysim.world.rows import MOTION_FIELDS, PAUSE, SPEED, STILL, TARGET, TH, VEL, Mover, X, Y


def wrap_angle(a: np.ndarray | float) -> np.ndarray | float:
    """Angle(s) wrapped to [-pi, pi) (``citysim.world.geometry.wrap_angle`` before the step was compiled)."""
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def must_wait(agents, pos, vel, length, width, s_along, leg_len) -> tuple[np.ndarray, np.ndarray]:
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


_MOTION_ROWS = {
    cls: tuple(getattr(k.motion, f) for f in MOTION_FIELDS) for cls, k in AGENT_KINDS.items()
}


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


def reference_move(agents: list[Mover], state: np.ndarray, vu: np.ndarray, dt: float, t_s: float) -> dict:
    """One step of the agents in the world's arrays, as numpy and pymunk took it: the moved poses
    (``x``, ``y``, ``th``: pymunk's integration), ``velocity``, ``speed``, ``target``, ``waiting``
    and the number of moves ``blocked``; on the way, the steps along and across (``ds``,
    ``step_lat``), the proposed poses after the overlap check (``new_x``, ``new_y``, ``new_th``) and
    how far each was cut back (``stage``)."""
    lay = Layout(tuple((a.oid, a.leg_i) for a in agents), agents)
    pos = np.array([tuple(row) for row in state[:, [X, Y]].tolist()])
    th = np.array(state[:, TH].tolist())
    vel = np.array([tuple(v) for v in vu[VEL].tolist()])
    dyn = np.array([tuple(row) for row in state[:, [SPEED, TARGET, STILL, PAUSE]].tolist()])
    patience = 1.0 / (1.0 + dyn[:, 2] / IMPATIENCE_S)
    v0 = np.where(dyn[:, 3] > t_s, 0.0, lay.v0)  # a pausing animal wants to stand
    rel = pos - lay.start
    s_along = np.einsum("ik,ik->i", rel, lay.unit)
    off = np.einsum("ik,ik->i", rel, lay.normal)
    nb = surroundings(lay, pos, th, vel, off, patience)
    wish = LateralWish(off, dyn[:, 1], lay.pref, lay.band, lay.comfort, patience, v0, lay.motion[8])

    target = lay.pref.copy()
    reachable = (nb.lat + nb.ext_l > (lay.band[:, 0] - nb.half)[:, None]) & (
        nb.lat - nb.ext_l < (lay.band[:, 1] + nb.half)[:, None]
    )
    rows = np.flatnonzero((nb.ahead & reachable | nb.beside).any(axis=1))
    if rows.size:
        target[rows] = choose_offsets(rows, wish, nb, lay.unit)

    wait_here, wait_at_end = must_wait(agents, pos, vel, lay.length, lay.width, s_along, lay.leg_len)
    target = np.where(wait_here, off, target)
    step_lat = lateral_step(lay, nb, off, target, dt)
    ds = forward_step(lay, nb, dyn[:, 0], v0, off, step_lat, dt)
    to_end = lay.leg_len - s_along
    ds = np.where(wait_at_end, np.minimum(ds, np.maximum(to_end - 0.01, 0.0) * (to_end > 0.05)), ds)
    ds = np.where(wait_here, 0.0, ds)
    return move_bodies(lay, (pos, th), (ds, step_lat, v0), (target, wait_here | wait_at_end), dt)


def move_bodies(lay: Layout, pose: tuple, step: tuple, intent: tuple, dt: float) -> dict:
    """The moves, cut back where they would overlap, handed to pymunk kinematic bodies and stepped."""
    (pos, th), (ds, step_lat, v0), (target, waiting) = pose, step, intent
    yaw_rate, max_tilt = lay.motion[9], lay.motion[10]
    new_pos = pos + ds[:, None] * lay.unit + step_lat[:, None] * lay.normal
    tilt = np.clip(np.arctan2(step_lat, np.maximum(ds, v0 * dt)), -max_tilt, max_tilt)
    want = lay.heading + tilt
    new_th = th + np.clip(wrap_angle(want - th), -yaw_rate * dt, yaw_rate * dt)
    along_pos = pos + ds[:, None] * lay.unit
    new_pos, new_th, stage = resolve_overlaps(pos, th, new_pos, new_th, along_pos, lay.length, lay.width)
    planned = {"ds": ds, "step_lat": step_lat, "new_x": new_pos[:, 0], "new_y": new_pos[:, 1], "new_th": new_th,
               "stage": stage.astype(float)}  # fmt: skip
    ds = np.where(stage < 3, ds, 0.0)

    velocity = ((new_pos - pos) / dt).tolist()
    omega = (wrap_angle(new_th - th) / dt).tolist()
    space = pymunk.Space()
    bodies = []
    for (x, y), a, v, w in zip(pos.tolist(), th.tolist(), velocity, omega, strict=True):
        body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        body.position, body.angle = (x, y), a
        body.velocity, body.angular_velocity = tuple(v), w
        space.add(body)
        bodies.append(body)
    space.step(dt)
    return {
        "x": np.array([b.position[0] for b in bodies]), "y": np.array([b.position[1] for b in bodies]),
        "th": np.array([b.angle for b in bodies]), "velocity": np.array(velocity).reshape(-1, 2),
        "speed": ds / dt, "target": target, "waiting": waiting.astype(float), "blocked": int((stage == 3).sum()),
    } | planned  # fmt: skip
