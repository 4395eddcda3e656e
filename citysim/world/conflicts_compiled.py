"""Giving way at a crossing, compiled (numba): which walkers must wait at the kerb this step.

A walker crosses when every vehicle and cyclist heading for the crossing arrives only after the
walker has left that road user's strip of road (plus ``CROSSING_MARGIN_S``): the near lane may be
crossed in a gap the far lane would not give. The same floating-point operations in the same
order as the numpy statement of the rule this replaced; the road users' speeds (``np.hypot``)
come in computed by numpy.

Conventions: world frame, metres, seconds, m/s; ``state`` and ``vu`` as in ``citysim.world.rows``.
"""

from __future__ import annotations

from citysim.world.jit import inlined, leaf
from citysim.world.rows import (
    LEG_LEN,
    LENGTH,
    NEXT_YIELD,
    NSX,
    ROAD,
    SX,
    UNIT,
    V0,
    WIDTH,
    YIELD,
    X,
    Y,
)

#: Extra time a crossing walker wants between the crossing and the next road user, s.
CROSSING_MARGIN_S = 1.5
#: ``must_wait``'s answers: free to go, wait at the start of the crossing, wait at the end of the
#: leg before it
GO, WAIT_HERE, WAIT_AT_END = 0.0, 1.0, 2.0


@leaf
def crossing_ahead(state, i, s_along):  # pragma: no cover - compiled
    """(kind, crossing row's first column) for walker i: ``WAIT_HERE`` and ``SX`` at the start of a
    crossing, ``WAIT_AT_END`` and ``NSX`` near the end of the leg before one, else ``GO``."""
    if state[i, YIELD] != 0 and s_along < 0.3:
        return WAIT_HERE, SX
    if state[i, NEXT_YIELD] != 0 and state[i, LEG_LEN] - s_along < 3.0:
        return WAIT_AT_END, NSX
    return GO, SX


@leaf
def arrives_first(state, vu, speed, i, crossing):  # pragma: no cover - compiled
    """Does some road user reach the crossing (start x, y, end x, y, length) before walker i has
    left its strip of road?"""
    sx, sy, ex, ey, length = crossing
    width = state[i, WIDTH]
    pad = width / 2 + 0.5
    x_lo = (ex if ex < sx else sx) - pad  # Python's min and max: the first on a tie
    x_hi = (ex if ex > sx else sx) + pad
    dy = ey - sy
    pace = state[i, V0] if not 0.5 > state[i, V0] else 0.5
    for j in range(state.shape[0]):
        if state[j, ROAD] == 0:
            continue
        ux = vu[UNIT, j, 0]
        r_dir = 1.0 if ux > 0 else (-1.0 if ux < 0 else 0.0)
        half = r_dir * state[j, LENGTH] / 2
        front, rear = state[j, X] + half, state[j, X] - half
        past = rear > x_hi if r_dir > 0 else rear < x_lo
        dist = x_lo - front if r_dir > 0 else front - x_hi
        t_arrive = (dist if dist > 0.0 else 0.0) / (speed[j] if speed[j] > 0.1 else 0.1)
        cleared_m = (abs(state[j, Y] - sy) + (state[j, WIDTH] + width) / 2) * length / abs(dy)
        t_leave = cleared_m / pace + CROSSING_MARGIN_S
        if not past and t_arrive < t_leave:
            return True
    return False


@inlined
def must_wait(state, vu, speed, s_along, out):  # pragma: no cover - compiled
    """Per agent into ``out``: ``GO``, or the walker must give way ``WAIT_HERE`` (at the start of
    its crossing) or ``WAIT_AT_END`` (at the end of the leg before it). ``speed``: each agent's
    speed (only read when some walker is near a crossing); ``s_along``: distance along its leg, m."""
    n = state.shape[0]
    out[:] = GO
    road = False
    for j in range(n):
        road |= state[j, ROAD] != 0
    if not road:
        return
    for i in range(n):
        if state[i, ROAD] != 0:
            continue
        kind, c = crossing_ahead(state, i, s_along[i])
        if kind == GO:
            continue
        crossing = (state[i, c], state[i, c + 1], state[i, c + 2], state[i, c + 3], state[i, c + 4])
        if arrives_first(state, vu, speed, i, crossing):
            out[i] = kind


@inlined
def needs_speeds(state, s_along):  # pragma: no cover - compiled
    """Will ``must_wait`` read the speeds this step (a walker near a crossing, a road user about)?"""
    road, walker = False, False
    for i in range(state.shape[0]):
        if state[i, ROAD] != 0:
            road = True
        elif crossing_ahead(state, i, s_along[i])[0] != GO:
            walker = True
    return road and walker
