"""The behaviour model's rules compiled (numba): every agent's lateral target and step along and
across its leg for one physics step (``plan``), as ``citysim.world.behaviour`` states them.

The same floating-point operations in the same order as the numpy statement of the rules that
this replaced (so the trajectories are the same, bit for bit), down to the sign of a zero:
``np.einsum`` over two components is ``0.0 + (a0 * b0 + a1 * b1)``; ``np.maximum(a, b)`` and
``np.minimum(a, b)`` answer ``b`` on a tie; ``np.clip`` of arrays answers the bound on a tie, but
with its bounds broadcast along the last axis (numpy's vector loop) ``x``; ``np.linspace`` is
``k * step + start`` with the end set to ``stop``. No transcendental function is called here:
the cosines and sines of the heading differences, the matrix of velocities along the legs (a
BLAS product: fused multiply-adds) and ``(v / v0) ** 4`` (libm ``pow``) come in computed by
numpy. Compiled as ``citysim.world.jit`` says: cached on disk, no parallelism, no fast-math.

Conventions: world frame, metres, seconds, m/s; angles rad CCW from +x; offsets metres to the
left of the leg direction. Arrays: ``state`` (N, ``rows.N_COLUMNS``) and ``vu`` (2, N, 2) of
``citysim.world.rows``; ``trig`` (2, N, N): cos and sin of
``th[j] - heading[i]``; ``v_dot`` (N, N): ``v_dot[j, i]`` = velocity of j . direction of i.
"""

from __future__ import annotations

import numpy as np

from citysim.world.conflicts_compiled import must_wait
from citysim.world.jit import inlined, kernel, leaf
from citysim.world.rows import (
    ACC,
    B_COMF,
    B_MAX,
    BAND_HI,
    BAND_LO,
    COMF_HI,
    COMF_LO,
    HEADWAY,
    HORIZON,
    LEG_LEN,
    LENGTH,
    LOOK,
    MARGIN,
    PAUSE,
    PREF,
    S0,
    SPEED,
    STILL,
    SX,
    SY,
    TARGET,
    UNIT,
    V0,
    V_LAT,
    WIDTH,
    X,
    Y,
)

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
#: Columns of ``plan``'s output: step along, step across, lateral target, waiting at the kerb
#: (1.0: at the start of the crossing, 2.0: at the end of the leg before it), the tilt's run
#: (max(step along, desired speed * dt)) and the desired speed (0 while pausing).
DS, STEP_LAT, NEW_TARGET, WAIT, TILT_RUN, WANT_V = range(6)
N_PLAN = 6


@leaf
def np_max(a, b):  # pragma: no cover - compiled
    """``np.maximum(a, b)`` of two floats that are not NaN."""
    return a if a > b else b


@leaf
def np_min(a, b):  # pragma: no cover - compiled
    """``np.minimum(a, b)`` of two floats that are not NaN."""
    return a if a < b else b


@leaf
def clip(x, lo, hi):  # pragma: no cover - compiled
    """``np.clip`` of arrays elementwise (lo <= hi, not NaN): min(max(x, lo), hi), the bound on a tie."""
    m = x if x > lo else lo
    return m if m < hi else hi


@leaf
def clip_keep(x, lo, hi):  # pragma: no cover - compiled
    """``np.clip`` with bounds broadcast along the last axis (numpy's SIMD loop): x on a tie."""
    return lo if x < lo else (hi if x > hi else x)


@inlined
def leg_frame(state, vu, t_s):  # pragma: no cover - compiled
    """Per agent: (distance along its leg, offset, patience, desired speed now)."""
    n = state.shape[0]
    s_along, off, patience, v0 = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    for i in range(n):
        rx, ry = state[i, X] - state[i, SX], state[i, Y] - state[i, SY]
        ux, uy = vu[UNIT, i, 0], vu[UNIT, i, 1]
        s_along[i] = 0.0 + (rx * ux + ry * uy)
        off[i] = 0.0 + (rx * -uy + ry * ux)
        patience[i] = 1.0 / (1.0 + state[i, STILL] / IMPATIENCE_S)
        v0[i] = 0.0 if state[i, PAUSE] > t_s else state[i, V0]  # a pausing animal wants to stand
    return s_along, off, patience, v0


@inlined
def surroundings(state, vu, trig, v_dot, off, patience):  # pragma: no cover - compiled
    """Every pair seen from each one's leg frame, [i, j]: j as i sees it.

    Returns (lat, ext_l, gap, v_along, ahead, beside) as (N, N) arrays and (self_l, half) per agent."""
    n = state.shape[0]
    fwd, lat, ext_f, ext_l = np.empty((n, n)), np.empty((n, n)), np.empty((n, n)), np.empty((n, n))
    v_along = np.empty((n, n))
    for i in range(n):
        ux, uy = vu[UNIT, i, 0], vu[UNIT, i, 1]
        for j in range(n):
            dx, dy = state[j, X] - state[i, X], state[j, Y] - state[i, Y]
            fwd[i, j] = 0.0 + (dx * ux + dy * uy)
            lat[i, j] = off[i] + (0.0 + (dx * -uy + dy * ux))
            c, s = abs(trig[0, i, j]), abs(trig[1, i, j])
            half_len, half_wid = state[j, LENGTH] / 2, state[j, WIDTH] / 2
            ext_f[i, j] = half_len * c + half_wid * s
            ext_l[i, j] = half_len * s + half_wid * c
            v_along[i, j] = v_dot[j, i]
    gap = np.empty((n, n))
    # every boolean array of the step is np.empty and then written whole: np.zeros would compile
    # numba's zeros and zero-fill kernels too, on a fresh clone's critical path
    ahead, beside = np.empty((n, n), np.bool_), np.empty((n, n), np.bool_)
    self_l, half = np.empty(n), np.empty(n)
    for i in range(n):
        self_f, self_l[i] = ext_f[i, i], ext_l[i, i]
        half[i] = self_l[i] + state[i, MARGIN] * patience[i]  # the held-up squeeze past with less clearance
        for j in range(n):
            gap[i, j] = fwd[i, j] - ext_f[i, j] - self_f
            ahead[i, j] = j != i and fwd[i, j] > 0 and gap[i, j] < state[i, LOOK]
            beside[i, j] = j != i and abs(fwd[i, j]) < ext_f[i, j] + self_f + 0.3
    return (lat, ext_l, gap, v_along, ahead, beside), (self_l, half)


@leaf
def candidates(lo, hi, off, target_prev, pref, uniform_steps):  # pragma: no cover - compiled
    """The lateral candidates: where it is, where it aimed, where it prefers, and
    ``N_LATERAL_CANDIDATES`` evenly over the band [lo, hi] (``np.linspace``; ``uniform_steps``
    False: numpy's way when some band of the batch is empty), all but the first in the band."""
    k = N_LATERAL_CANDIDATES
    cands = np.empty(3 + k)
    cands[0], cands[1], cands[2] = off, target_prev, pref
    delta = hi - lo
    step = delta / (k - 1)
    for m in range(k - 1):
        cands[3 + m] = (m * step if uniform_steps else (m / (k - 1)) * delta) + lo
    cands[3 + k - 1] = hi
    for c in range(1, 3 + k):
        cands[c] = clip_keep(cands[c], lo, hi)
    return cands


@leaf
def facing_edge(i, state, vu, trig, nb, in_lane0, reach_max):  # pragma: no cover - compiled
    """Facing someone oncoming in its way: the band edge agent i steps to, else NaN.

    To its right if they are on its left or dead ahead, else to its left: both parties do, which
    clears the way whenever two can pass at all. The side is judged in a frame both share (axis:
    my direction minus theirs), so the two always pick opposite ways even on skew paths."""
    gap, ahead = nb[2], nb[4]
    nearest, best = -1, np.inf
    for j in range(state.shape[0]):
        if ahead[i, j] and in_lane0[j] and trig[0, i, j] < -0.5 and gap[i, j] < reach_max + 2.0:
            if gap[i, j] < best or nearest < 0:
                nearest, best = j, gap[i, j]
    if nearest < 0:
        return np.nan
    ax = vu[UNIT, i, 0] - vu[UNIT, nearest, 0]
    ay = vu[UNIT, i, 1] - vu[UNIT, nearest, 1]
    rx, ry = state[nearest, X] - state[i, X], state[nearest, Y] - state[i, Y]
    on_left = ry * ax - rx * ay >= 0
    return state[i, BAND_LO] if on_left else state[i, BAND_HI]


@inlined
def choose_offset(i, state, vu, trig, nb, own, uniform_steps):  # pragma: no cover - compiled
    """Agent i's best lateral offset: the candidate with the most free distance within its
    horizon (minus reluctance), among those reachable without sweeping into anyone beside.

    ``own`` = (off, patience, v0, half, self_l) per agent."""
    off_all, patience, v0, half_all = own[0], own[1], own[2], own[3]
    lat, ext_l, gap, v_along, ahead, beside = nb
    n = state.shape[0]
    off, half, horizon = off_all[i], half_all[i], state[i, HORIZON]
    target_prev, pref = state[i, TARGET], state[i, PREF]
    cands = candidates(state[i, BAND_LO], state[i, BAND_HI], off, target_prev, pref, uniform_steps)
    reach_max = v0[i] * horizon
    in_lane0 = np.empty(n, np.bool_)  # written whole for the first candidate
    score = np.empty(cands.size)
    infeasible = np.empty(cands.size, np.bool_)
    for c in range(cands.size):
        cand = cands[c]
        infeasible[c] = False
        blocked_min = np.inf
        sweep_lo, sweep_hi = np_min(off, cand) - half, np_max(off, cand) + half
        for j in range(n):
            in_lane = abs(lat[i, j] - cand) < ext_l[i, j] + half
            if c == 0:
                in_lane0[j] = in_lane
            if ahead[i, j] and in_lane:
                blocked_min = min(blocked_min, gap[i, j] + v_along[i, j] * horizon)
            if beside[i, j]:
                hi_side, lo_side = lat[i, j] + ext_l[i, j], lat[i, j] - ext_l[i, j]
                touch_now = hi_side > off - half and lo_side < off + half
                if hi_side > sweep_lo and lo_side < sweep_hi and not touch_now:
                    infeasible[c] = True
        free = np_min(blocked_min, reach_max)
        comfort = np_max(0.0, state[i, COMF_LO] - cand) + np_max(0.0, cand - state[i, COMF_HI])
        reluctance = W_PREF * abs(cand - pref) + W_COMFORT * comfort + W_KEEP * abs(cand - target_prev)
        score[c] = free - patience[i] * reluctance
    edge = facing_edge(i, state, vu, trig, nb, in_lane0, reach_max)
    best = 0
    for c in range(cands.size):
        if not np.isnan(edge):
            score[c] = -abs(cands[c] - edge)
        if infeasible[c]:  # never column 0: staying at the current offset sweeps nothing
            score[c] = -np.inf
        if score[c] > score[best]:
            best = c
    return cands[best]


@inlined
def lateral_step(i, state, nb, own, target, dt):  # pragma: no cover - compiled
    """Agent i's sideways step toward ``target`` this step, stopping short of anyone beside, m."""
    lat, ext_l, beside = nb[0], nb[1], nb[5]
    off, self_l = own[0][i], own[4][i]
    v_lat = state[i, V_LAT]
    step = clip(target - off, -v_lat * dt, v_lat * dt)
    room_left, room_right = np.inf, np.inf
    for j in range(state.shape[0]):
        if beside[i, j] and lat[i, j] > off:
            room_left = min(room_left, lat[i, j] - ext_l[i, j] - (off + self_l))
        if beside[i, j] and lat[i, j] < off:
            room_right = min(room_right, (off - self_l) - (lat[i, j] + ext_l[i, j]))
    # the one beside may step toward me in the same step: each takes half the room
    room_left, room_right = (room_left - CLEARANCE_M) / 2, (room_right - CLEARANCE_M) / 2
    return clip(step, -np_max(room_right, 0.0), np_max(room_left, 0.0))


@inlined
def forward_step(i, state, nb, own, step_lat, dt, free_term):  # pragma: no cover - compiled
    """Agent i's step along its leg: the Intelligent Driver Model behind the leader in the
    corridor its sideways step sweeps, never more than the room left to that leader, m."""
    lat, ext_l, gap, v_along, ahead = nb[0], nb[1], nb[2], nb[3], nb[4]
    off, v0, half = own[0][i], own[2][i], own[3][i]
    off_new = off + step_lat
    c_lo, c_hi = np_min(off, off_new) - half, np_max(off, off_new) + half
    g, lead = np.inf, -1
    for j in range(state.shape[0]):
        if ahead[i, j] and lat[i, j] + ext_l[i, j] > c_lo and lat[i, j] - ext_l[i, j] < c_hi:
            if gap[i, j] < g:
                g, lead = gap[i, j], j
    has_lead = lead >= 0
    v_lead = v_along[i, lead] if has_lead else 0.0
    v = np_max(state[i, SPEED], 0.0)
    acc_max, b_comf = state[i, ACC], state[i, B_COMF]
    s_star = state[i, S0] + np_max(0.0, v * state[i, HEADWAY] + v * (v - v_lead) / (2.0 * np.sqrt(acc_max * b_comf)))
    inter = 0.0
    if has_lead:
        ratio = s_star / np_max(g, 0.01)
        inter = ratio * ratio
    acc = clip(acc_max * (free_term - inter), -state[i, B_MAX], acc_max)
    v_new = clip(v + acc * dt, 0.0, v0)
    # never exceed the desired speed in total (forward and sideways together)
    lat_v = step_lat / dt
    v_new = np_min(v_new, np.sqrt(np_max(v0 * v0 - lat_v * lat_v, 0.0)))
    ds = v_new * dt
    if not has_lead:
        return ds
    room = (g / 2 if v_lead < -0.05 else g) - CLEARANCE_M  # half the gap to an oncoming one
    return np_min(ds, np_max(room, 0.0))


@kernel
def plan(state, vu, trig, v_dot, q4, dt, t_s, out):  # pragma: no cover - compiled
    """Every agent's move for the next ``dt`` seconds into ``out`` (rows ``DS`` .. ``WANT_V``).

    ``q4``: (max(speed, 0) / max(v0, 1e-9)) ** 4 per agent (``moves_compiled.prepare``'s ratio,
    raised by numpy), and in its second row each agent's speed (``np.hypot`` of its velocity) when
    some walker gives way. ``out`` is (columns, N); ``state`` is read only."""
    n = state.shape[0]
    s_along, off, patience, v0 = leg_frame(state, vu, t_s)
    nb, (self_l, half) = surroundings(state, vu, trig, v_dot, off, patience)
    own = (off, patience, v0, half, self_l)
    lat, ext_l, ahead, beside = nb[0], nb[1], nb[4], nb[5]
    # ---- lateral choice (only agents with someone ahead or beside; the rest head for pref)
    rows = np.empty(n, np.bool_)
    n_point_bands = 0
    for i in range(n):
        lo, hi = state[i, BAND_LO] - half[i], state[i, BAND_HI] + half[i]
        rows[i] = False
        for j in range(n):
            reachable = lat[i, j] + ext_l[i, j] > lo and lat[i, j] - ext_l[i, j] < hi
            rows[i] |= ahead[i, j] and reachable or beside[i, j]
        if rows[i] and (state[i, BAND_HI] - state[i, BAND_LO]) / (N_LATERAL_CANDIDATES - 1) == 0:
            n_point_bands += 1
    # some band empty: numpy's linspace then divides before it multiplies, for all. A comparison,
    # not a flag set to True or False: numba would type a constant flag as a literal and compile
    # choose_offset (and candidates) twice, once for the literal True and once for bool
    uniform_steps = n_point_bands == 0
    for i in range(n):
        out[NEW_TARGET, i] = choose_offset(i, state, vu, trig, nb, own, uniform_steps) if rows[i] else state[i, PREF]
    # ---- giving way at the kerb
    must_wait(state, vu, q4[1], s_along, out[WAIT])
    for i in range(n):
        wait = out[WAIT, i]
        if wait == 1.0:
            out[NEW_TARGET, i] = off[i]
        step_lat = lateral_step(i, state, nb, own, out[NEW_TARGET, i], dt)
        free_term = 1.0 - q4[0, i] if v0[i] > 0 else -1.0
        ds = forward_step(i, state, nb, own, step_lat, dt, free_term)
        # a walker that must give way stops at the kerb (end of its leg, or start of the crossing)
        to_end = state[i, LEG_LEN] - s_along[i]
        if wait == 2.0:
            ds = np_min(ds, np_max(to_end - 0.01, 0.0) * (1.0 if to_end > 0.05 else 0.0))
        if wait == 1.0:
            ds = 0.0
        out[DS, i], out[STEP_LAT, i], out[WANT_V, i] = ds, step_lat, v0[i]
        out[TILT_RUN, i] = np_max(ds, v0[i] * dt)
