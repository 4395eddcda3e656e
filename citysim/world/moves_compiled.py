"""Moving the agents, compiled (numba): the inputs numpy turns into cosines and powers, the
proposed poses, the velocities that make the agreed moves, the exchange with the pymunk bodies,
and what changes with the distance walked.

Each agent is a pymunk kinematic body (``citysim.world.bodies``): ``commit`` sets the velocity
and angular velocity that carry it to its agreed pose over the step, ``Space.step`` integrates
them (``p + v dt``, ``a + w dt``), and ``from_bodies`` reads the poses back into the rows.
The same floating-point operations in the same order as the numpy statement of the rules this
replaced; arctan2 and the overlap check's geometry stay in numpy. Compiled as ``citysim.world.jit``
says: cached on disk, no parallelism, no fast-math.

Conventions: world frame, metres, seconds, m/s; angles rad CCW from +x; ``state`` and ``vu`` as in
``citysim.world.rows``; ``plan`` as ``citysim.world.behaviour_compiled.plan`` leaves it.
"""

from __future__ import annotations

import math

from citysim.world.behaviour_compiled import (
    DS,
    N_PLAN,
    NEW_TARGET,
    STEP_LAT,
    WAIT,
    clip,
    leg_frame,
    np_max,
)
from citysim.world.conflicts_compiled import needs_speeds
from citysim.world.jit import inlined, kernel
from citysim.world.rows import (
    HEADING,
    LEG_LEN,
    OMEGA,
    PAUSE,
    PHASE,
    REACH,
    SPEED,
    STILL,
    STRIDE,
    SX,
    SY,
    TARGET,
    TH,
    TILT,
    UNIT,
    V0,
    VEL,
    WAITING,
    YAW,
    X,
    Y,
)

PI = math.pi
TWO_PI = 2.0 * math.pi
#: Rows of the step's work array (after ``plan``'s): the arctan2 of the swerve (in), the new pose,
#: the pose after the step along alone, and the stage the overlap check cut the move back to
#: (0 as proposed, 1 turn dropped, 2 sidestep dropped, 3 stayed put).
TILT_RAW, NEW_X, NEW_Y, NEW_TH, ALONG_X, ALONG_Y, STAGE = range(N_PLAN, N_PLAN + 7)
N_WORK = N_PLAN + 7
#: The proposed poses go to the exact (numpy) overlap check when some pair's squared distance is
#: under (1 + NEAR_SLACK) times the square of their bounding radii's sum: numpy's check looks at
#: the pair when ``np.hypot`` of the distance is under the sum, and hypot errs by under an ulp.
NEAR_SLACK = 1e-9


@kernel
def wrap_angle(a):  # pragma: no cover - compiled
    """Angle ``a`` wrapped to [-pi, pi): (a + pi) % 2 pi - pi, as numpy's remainder computes it."""
    return (a + PI) % TWO_PI - PI


@kernel
def prepare(state, vu, t_s, phi, ratio):  # pragma: no cover - compiled
    """What numpy computes the step's transcendental inputs from: ``phi[i, j]`` = heading of j
    less the direction of i's leg; ``ratio`` = max(speed, 0) / max(desired speed now, 1e-9).
    Returns whether the walkers' giving way will need the agents' speeds."""
    n = state.shape[0]
    for i in range(n):
        for j in range(n):
            phi[i, j] = state[j, TH] - state[i, HEADING]
        v0 = 0.0 if state[i, PAUSE] > t_s else state[i, V0]
        v = np_max(state[i, SPEED], 0.0)
        ratio[i] = v / np_max(v0, 1e-9)
    return needs_speeds(state, leg_frame(state, vu, t_s)[0])


@inlined
def propose(state, vu, work, dt):  # pragma: no cover - compiled
    """The new poses of the planned moves into ``work``: facing along the leg, riders and
    drivers tilted into a swerve (``TILT_RAW``: numpy's arctan2 of the sidestep over
    ``TILT_RUN``), turning at most their yaw rate. Returns whether some pair may overlap (their
    bounding circles meet): then numpy's exact check must cut moves back before ``commit``."""
    n = state.shape[0]
    for i in range(n):
        ds, step_lat = work[DS, i], work[STEP_LAT, i]
        ux, uy = vu[UNIT, i, 0], vu[UNIT, i, 1]
        work[ALONG_X, i] = state[i, X] + ds * ux
        work[ALONG_Y, i] = state[i, Y] + ds * uy
        work[NEW_X, i] = work[ALONG_X, i] + step_lat * -uy
        work[NEW_Y, i] = work[ALONG_Y, i] + step_lat * ux
        tilt = clip(work[TILT_RAW, i], -state[i, TILT], state[i, TILT])
        th, turn = state[i, TH], state[i, YAW] * dt
        work[NEW_TH, i] = th + clip(wrap_angle((state[i, HEADING] + tilt) - th), -turn, turn)
        work[STAGE, i] = 0.0
    for i in range(n):
        for j in range(i + 1, n):
            dx, dy = work[NEW_X, j] - work[NEW_X, i], work[NEW_Y, j] - work[NEW_Y, i]
            r = state[i, REACH] + state[j, REACH]
            if dx * dx + dy * dy < r * r * (1.0 + NEAR_SLACK):
                return True
    return False


@inlined
def commit(state, vu, work, dt):  # pragma: no cover - compiled
    """The velocities that make the agreed moves over ``dt`` (``VEL``, ``OMEGA``: for the bodies to
    integrate); the number of moves the overlap check cancelled. Sets each agent's velocity,
    angular velocity, speed, lateral target and waiting flag; its pose is left to its body."""
    blocked = 0
    for i in range(state.shape[0]):
        stage = work[STAGE, i]
        if stage == 3:
            blocked += 1
        ds = work[DS, i] if stage < 3 else 0.0
        vu[VEL, i, 0] = (work[NEW_X, i] - state[i, X]) / dt
        vu[VEL, i, 1] = (work[NEW_Y, i] - state[i, Y]) / dt
        state[i, OMEGA] = wrap_angle(work[NEW_TH, i] - state[i, TH]) / dt
        state[i, SPEED] = ds / dt
        state[i, TARGET] = work[NEW_TARGET, i]
        state[i, WAITING] = 1.0 if work[WAIT, i] != 0 else 0.0
    return blocked


@kernel
def to_bodies(state, vu, rows, out):  # pragma: no cover - compiled
    """The bodies' velocities and angular velocities in the space's order, for ``pymunk.batch``:
    ``out[3 k : 3 k + 3]`` = (vx, vy, omega) of row ``rows[k]``."""
    for k in range(rows.shape[0]):
        i = rows[k]
        out[3 * k] = vu[VEL, i, 0]
        out[3 * k + 1] = vu[VEL, i, 1]
        out[3 * k + 2] = state[i, OMEGA]


@kernel
def from_bodies(poses, rows, state):  # pragma: no cover - compiled
    """The bodies' poses, in the space's order as ``pymunk.batch`` gives them (x, y, angle of each),
    into their rows ``rows[k]``."""
    for k in range(rows.shape[0]):
        i = rows[k]
        state[i, X] = poses[3 * k]
        state[i, Y] = poses[3 * k + 1]
        state[i, TH] = poses[3 * k + 2]


@kernel
def advance(state, vu, speed, dt, t_s, leg_done):  # pragma: no cover - compiled
    """After the move: gait phases (one cycle per stride), time held still by others, and
    ``leg_done[i]``: agent i has reached the end of its leg. ``speed``: each agent's speed
    (Python's ``math.hypot`` of its velocity). Returns how many reached a leg's end."""
    done = 0
    for i in range(state.shape[0]):
        dist = speed[i] * dt
        state[i, PHASE] = (state[i, PHASE] + TWO_PI * dist / state[i, STRIDE]) % TWO_PI
        held = speed[i] < 0.05 and state[i, WAITING] == 0 and state[i, PAUSE] < t_s
        state[i, STILL] = state[i, STILL] + dt if held else 0.0
        ux, uy = vu[UNIT, i, 0], vu[UNIT, i, 1]
        s = (state[i, X] - state[i, SX]) * ux + (state[i, Y] - state[i, SY]) * uy
        leg_done[i] = not s < state[i, LEG_LEN]
        if leg_done[i]:
            done += 1
    return done


@kernel
def move(state, vu, work, dt):  # pragma: no cover - compiled
    """``propose`` the planned moves and, if no pair may overlap, ``commit`` them: the number of
    moves cancelled, or -1 if numpy's exact overlap check must see them first."""
    if propose(state, vu, work, dt):
        return -1
    return commit(state, vu, work, dt)
