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

import numpy as np
import pymunk

from citysim.config.kinds import AGENT_KINDS
from citysim.world.agents import AgentTraits
from citysim.world.geometry import Leg, oriented_overlaps, wrap_angle

#: Lateral candidates evaluated per agent and step (evenly over the band).
N_LATERAL_CANDIDATES = 9
#: Score weights, metres of free distance per metre of offset: away from the
#: preferred side, outside the comfort band, and away from the last choice.
W_PREF, W_COMFORT, W_KEEP = 0.3, 1.5, 0.2
#: Impatience: an agent held still for t seconds weighs those reluctances by
#: 1 / (1 + t / IMPATIENCE_S), so two that block each other soon both give way.
IMPATIENCE_S = 2.0
#: Extra time a crossing walker wants between the crossing and the next road user, s.
CROSSING_MARGIN_S = 1.5
#: Clearance the behaviour keeps between footprints (sidestepping, closing up), m.
CLEARANCE_M = 0.01
#: Overlap the last-resort check tolerates: pymunk integrates p + v dt, which may
#: land a float rounding (~1e-14 m) away from the checked pose.
OVERLAP_TOLERANCE_M = 1e-9


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


def plan_moves(agents: list[Mover], lay: Layout, dt: float, t_s: float) -> int:
    """Decide every agent's move for the next ``dt`` seconds and hand it to its pymunk body.

    Sets each body's velocity and angular velocity (``Space.step`` then integrates
    them) and each agent's speed, lateral target and waiting flag. Returns the
    number of moves the last-resort overlap check dropped.
    """
    n = len(agents)
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
    v0 = np.where(dyn[:, 3] > t_s, 0.0, lay.v0)  # a pausing animal wants to stand

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
    half = self_l + margin * patience  # the held-up squeeze past with less clearance
    beside = others & (np.abs(fwd) < ext_f + self_f[:, None] + 0.3)

    # ---- lateral choice (only agents with someone ahead or beside; the rest head for pref)
    target = pref.copy()
    reachable = (lat + ext_l > (band[:, 0] - half)[:, None]) & (
        lat - ext_l < (band[:, 1] + half)[:, None]
    )
    rows = np.flatnonzero((ahead & reachable | beside).any(axis=1))
    if rows.size:
        target[rows] = choose_offsets(
            rows, off, target_prev, pref, band, comfort, patience, v0, horizon, half,
            lat, ext_l, gap, v_along, phi, ahead, beside, d, unit,
        )  # fmt: skip

    # ---- giving way at the kerb
    wait_here, wait_at_end = must_wait(agents, pos, vel, length, width, s_along, leg_len)
    target = np.where(wait_here, off, target)

    # ---- lateral step, stopping short of anyone beside
    step_lat = np.clip(target - off, -v_lat * dt, v_lat * dt)
    room_left = np.where(
        beside & (lat > off[:, None]), lat - ext_l - (off + self_l)[:, None], np.inf
    ).min(1)
    room_right = np.where(
        beside & (lat < off[:, None]), (off - self_l)[:, None] - (lat + ext_l), np.inf
    ).min(1)
    # the one beside may step toward me in the same step: each takes half the room
    room_left, room_right = (room_left - CLEARANCE_M) / 2, (room_right - CLEARANCE_M) / 2
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
    ds = np.where(wait_at_end, np.minimum(ds, np.maximum(to_end - 0.01, 0.0) * (to_end > 0.05)), ds)
    ds = np.where(wait_here, 0.0, ds)

    # ---- proposed poses; drop moves that would overlap
    new_pos = pos + ds[:, None] * unit + step_lat[:, None] * normal
    # face along the leg; riders and drivers tilt into a swerve (a slow one does
    # not turn on the spot), walkers and animals sidestep facing forward, which
    # also keeps side-by-side footprints parallel
    tilt = np.clip(np.arctan2(step_lat, np.maximum(ds, v0 * dt)), -max_tilt, max_tilt)
    want = lay.heading + tilt
    new_th = th + np.clip(wrap_angle(want - th), -yaw_rate * dt, yaw_rate * dt)
    along_pos = pos + ds[:, None] * unit
    new_pos, new_th, stage = resolve_overlaps(pos, th, new_pos, new_th, along_pos, length, width)
    ds = np.where(stage < 3, ds, 0.0)

    velocity = ((new_pos - pos) / dt).tolist()
    omega = (wrap_angle(new_th - th) / dt).tolist()
    rows = zip(
        agents,
        velocity,
        omega,
        (ds / dt).tolist(),
        target.tolist(),
        (wait_here | wait_at_end).tolist(),
        strict=True,
    )
    for a, vel_i, omega_i, speed_i, target_i, waiting_i in rows:
        a.body.velocity = a.velocity = tuple(vel_i)
        a.body.angular_velocity = omega_i
        a.speed_mps, a.target_m, a.waiting = speed_i, target_i, waiting_i
    return int((stage == 3).sum())


def choose_offsets(
    rows, off, target_prev, pref, band, comfort, patience, v0, horizon, half,
    lat, ext_l, gap, v_along, phi, ahead, beside, d, unit,
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


def resolve_overlaps(pos, th, new_pos, new_th, along_pos, length, width) -> tuple:
    """Cut back moves that would overlap until no moved pair does.

    A culprit first keeps its old heading, then also drops its sideways step
    (keeping ``along_pos``, the move along its leg), then stays where it was.
    Old poses never overlap, so this ends. Returns (poses, headings, stage per
    agent: 0 as proposed, 1 turn dropped, 2 sidestep dropped, 3 stayed put).
    """
    n = len(pos)
    stage = np.zeros(n, dtype=int)
    reach = np.hypot(length, width) / 2
    d = new_pos[None, :, :] - new_pos[:, None, :]
    near = np.hypot(d[..., 0], d[..., 1]) < reach[:, None] + reach[None, :]
    np.fill_diagonal(near, False)
    if not near.any():  # bounding circles apart: nothing can overlap
        return new_pos, new_th, stage
    new_pos, new_th = new_pos.copy(), new_th.copy()
    for _ in range(3 * n + 1):
        moved = stage < 3
        hit = oriented_overlaps(new_pos, new_th, length, width, margin_m=-OVERLAP_TOLERANCE_M)
        hit &= moved[:, None] | moved[None, :]
        culprit = hit.any(axis=1) & moved
        if not culprit.any():
            break
        stage[culprit] += 1
        new_th[culprit] = th[culprit]
        sidestep = culprit & (stage == 2)
        new_pos[sidestep] = along_pos[sidestep]
        stay = culprit & (stage == 3)
        new_pos[stay] = pos[stay]
    return new_pos, new_th, stage
