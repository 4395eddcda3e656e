"""Conflicts between moving agents: who gives way at a crossing, and which moves are cut back so
that no two footprints overlap (the last resort after the behaviour model's own spacing).

Conventions: world frame, metres, seconds; positions (N, 2), headings rad CCW from +x.
"""

from __future__ import annotations

import numpy as np

from citysim.world.geometry import oriented_overlaps

#: Extra time a crossing walker wants between the crossing and the next road user, s.
CROSSING_MARGIN_S = 1.5
#: Overlap the last-resort check tolerates: pymunk integrates p + v dt, which may
#: land a float rounding (~1e-14 m) away from the checked pose.
OVERLAP_TOLERANCE_M = 1e-9


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
