"""Conflicts between moving agents: which moves are cut back so that no two footprints overlap
(the last resort after the behaviour model's own spacing). Who gives way at a crossing is
decided compiled (``citysim.world.conflicts_compiled``); this check stays in numpy (it is needed
in few steps: only when bounding circles meet).

Conventions: world frame, metres, seconds; positions (N, 2), headings rad CCW from +x.
"""

from __future__ import annotations

import numpy as np

from citysim.world.geometry import oriented_overlaps

#: Overlap the last-resort check tolerates: a body integrates p + v dt, which may
#: land a float rounding (~1e-14 m) away from the checked pose.
OVERLAP_TOLERANCE_M = 1e-9


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
