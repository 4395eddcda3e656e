"""How agents decide their motion, each physics step, over all agents at once.

``move_agents`` reads every agent's pose and route and decides its next move (longitudinal:
the Intelligent Driver Model; lateral: ``choose_offset``; giving way: ``must_wait``; no overlap:
``resolve_overlaps``) as the velocity and angular velocity its pymunk kinematic body is given
for the step (``citysim.world.bodies``). The rules run compiled (numba), the same bit for bit on
any machine.

Conventions: world frame of docs/design/architecture.md; offsets are metres to the left of the
leg direction (``citysim.world.geometry``); speeds m/s; angles rad CCW from +x.

Design: docs/design/modules.md (Agent behaviour)
"""

from __future__ import annotations

import numpy as np

from citysim.world.behaviour_compiled import STEP_LAT, TILT_RUN, plan
from citysim.world.conflicts import resolve_overlaps
from citysim.world.moves_compiled import (
    ALONG_X,
    ALONG_Y,
    N_WORK,
    NEW_TH,
    NEW_X,
    NEW_Y,
    STAGE,
    TILT_RAW,
    commit,
    move,
    prepare,
)
from citysim.world.rows import LENGTH, TH, UNIT, VEL, WIDTH, X, Y

__all__ = ["move_agents"]


def move_agents(state: np.ndarray, vu: np.ndarray, dt: float, t_s: float, work: np.ndarray | None = None) -> int:
    """Decide every agent's move for the next ``dt`` seconds (``citysim.world.rows``' arrays,
    updated in place): velocity and angular velocity (for its body to integrate), speed, lateral
    target, waiting flag.

    Returns the number of moves the last-resort overlap check dropped. ``work``: an array
    (``moves_compiled.N_WORK``, N) to leave the step's plan and proposed poses in (tests)."""
    n = len(state)
    phi, ratio = np.empty((n, n)), np.empty(n)
    needs_speeds = prepare(state, vu, t_s, phi, ratio)
    trig = np.empty((2, n, n))
    np.cos(phi, out=trig[0])
    np.sin(phi, out=trig[1])
    v_dot = vu[VEL] @ vu[UNIT].T  # v_dot[j, i] = vel_j . unit_i
    q4 = np.zeros((2, n))
    np.power(ratio, 4, out=q4[0])  # the IDM's free-road term
    if needs_speeds:
        np.hypot(vu[VEL, :, 0], vu[VEL, :, 1], out=q4[1])
    work = np.empty((N_WORK, n)) if work is None else work
    plan(state, vu, trig, v_dot, q4, dt, t_s, work)
    # riders and drivers tilt into a swerve (a slow one does not turn on the spot)
    np.arctan2(work[STEP_LAT], work[TILT_RUN], out=work[TILT_RAW])
    blocked = move(state, vu, work, dt)
    if blocked < 0:  # bounding circles meet: the exact check first
        _cut_back(state, work)
        blocked = commit(state, vu, work, dt)
    return blocked


def _cut_back(state: np.ndarray, work: np.ndarray) -> None:
    """Numpy's exact overlap check over the proposed poses in ``work``: moves that would overlap are
    cut back there (``STAGE`` says how far)."""
    pos = np.ascontiguousarray(state[:, [X, Y]])
    new_pos = np.stack([work[NEW_X], work[NEW_Y]], axis=1)
    along_pos = np.stack([work[ALONG_X], work[ALONG_Y]], axis=1)
    length, width = state[:, LENGTH].copy(), state[:, WIDTH].copy()
    new_pos, new_th, stage = resolve_overlaps(pos, state[:, TH].copy(), new_pos, work[NEW_TH].copy(), along_pos, length, width)
    work[NEW_X], work[NEW_Y], work[NEW_TH], work[STAGE] = new_pos[:, 0], new_pos[:, 1], new_th, stage
