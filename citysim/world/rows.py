"""The moving agents as arrays: one row per agent in order of entry, what the compiled step reads.

``World`` keeps every agent's pose, motion state, looks and current (and next) leg in one float64
array of ``N_COLUMNS`` columns (flags as 0.0 / 1.0), and its velocity and leg direction in a
``(2, N, 2)`` array (``VEL``, ``UNIT``; each ``(N, 2)`` half C-contiguous, as the matrix product of
the behaviour wants them). The pose is the agent's pymunk body's, read back after every step
(``citysim.world.bodies``); ``VEL`` and ``OMEGA`` are the velocity and angular velocity handed to
it. ``Mover`` keeps what the compiled step never reads: the agent's id, traits, route and group
members' gait phases.

Conventions: world frame of docs/design/architecture.md, metres, seconds, m/s; angles rad CCW from +x; leg offsets
metres to the left of the leg direction (``citysim.world.geometry``).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from citysim.config.kinds import AGENT_KINDS
from citysim.world.agents import AgentTraits
from citysim.world.geometry import Leg

# the agent's pose and motion state
X, Y, TH, PHASE, SPEED, TARGET, STILL, PAUSE, WAITING = range(9)
# its looks and kind: size, desired speed, stride, road user (1.0) or walker, bounding radius
LENGTH, WIDTH, V0, STRIDE, ROAD, REACH = range(9, 15)
#: first of the kind's motion parameters, in the order of ``MOTION_FIELDS``
MOTION = 15
MOTION_FIELDS = (
    "accel_mps2", "comfort_decel_mps2", "max_decel_mps2", "headway_s", "min_gap_m", "lookahead_m",
    "lateral_speed_mps", "lateral_margin_m", "horizon_s", "yaw_rate_rps", "max_tilt_rad",
)  # fmt: skip
ACC, B_COMF, B_MAX, HEADWAY, S0, LOOK, V_LAT, MARGIN, HORIZON, YAW, TILT = range(MOTION, MOTION + 11)
# the leg it is on: heading, start, end, length, lateral band, comfort band, preferred offset,
# whether it crosses the road (walkers give way at its start)
HEADING, SX, SY, EX, EY, LEG_LEN, BAND_LO, BAND_HI, COMF_LO, COMF_HI, PREF, YIELD = range(26, 38)
# the next leg when it crosses the road (walkers wait at this leg's end): flag, start, end, length
NEXT_YIELD, NSX, NSY, NEX, NEY, NLEN = range(38, 44)
#: the angular velocity its body was given for the step, rad/s
OMEGA = 44
N_COLUMNS = 45
#: halves of the (2, N, 2) array: velocity (m/s) and leg direction (unit vector)
VEL, UNIT = 0, 1

_MOTION_ROWS = {cls: tuple(float(getattr(k.motion, f)) for f in MOTION_FIELDS) for cls, k in AGENT_KINDS.items()}


class Mover:
    """What the compiled step never reads about one agent: id, looks, route, group members."""

    __slots__ = ("oid", "traits", "legs", "leg_i", "member_phases", "road_user", "pauses")

    def __init__(self, oid: int, traits: AgentTraits, legs: tuple[Leg, ...]):
        self.oid = oid
        self.traits = traits
        self.legs = legs
        self.leg_i = 0
        self.member_phases = [m.gait_phase_rad for m in traits.members]
        kind = AGENT_KINDS[traits.cls]
        self.road_user = kind.road_user  # walkers give way to it
        self.pauses = kind.pauses  # animals stop now and then

    @property
    def leg(self) -> Leg:
        return self.legs[self.leg_i]


@lru_cache(maxsize=4096)
def _leg_columns(leg: Leg) -> tuple[tuple[float, float], tuple[float, ...]]:
    """A leg's direction and its columns ``HEADING`` .. ``YIELD``."""
    ux, uy = leg.unit
    # as numpy computes it over the agents' legs (``np.arctan2`` of arrays)
    heading = float(np.arctan2(np.array([uy]), np.array([ux]))[0])
    (sx, sy), (ex, ey) = leg.start_xy_m, leg.end_xy_m
    cols = (heading, sx, sy, ex, ey, leg.length_m, *leg.band_m, *leg.comfort_m, leg.pref_m, float(leg.yield_to_traffic))
    return (ux, uy), cols


def set_leg(state: np.ndarray, vu: np.ndarray, row: int, mover: Mover) -> None:
    """Write the mover's current leg (and its next one, if that crosses the road) into its row."""
    unit, cols = _leg_columns(mover.leg)
    vu[UNIT, row] = unit
    state[row, HEADING : YIELD + 1] = cols
    nxt = mover.legs[mover.leg_i + 1] if mover.leg_i + 1 < len(mover.legs) else None
    if nxt is not None and nxt.yield_to_traffic:
        state[row, NEXT_YIELD : NLEN + 1] = (1.0, *nxt.start_xy_m, *nxt.end_xy_m, nxt.length_m)
    else:
        state[row, NEXT_YIELD : NLEN + 1] = 0.0


def new_row(mover: Mover, pose: tuple[float, float, float], speed_mps: float) -> tuple[np.ndarray, np.ndarray]:
    """The state row (1, N_COLUMNS) and velocity / direction block (2, 1, 2) of an agent entering
    at ``pose`` = (x, y, heading) with ``speed_mps``, standing still so far."""
    t = mover.traits
    state = np.zeros((1, N_COLUMNS))
    vu = np.zeros((2, 1, 2))
    state[0, :WAITING + 1] = (*pose, t.gait_phase_rad, speed_mps, mover.leg.pref_m, 0.0, -1.0, 0.0)
    # the bounding radius, as numpy computes it over the agents (``np.hypot`` of arrays)
    reach = np.hypot(np.array([t.length_m]), np.array([t.width_m])) / 2
    state[0, LENGTH : REACH + 1] = (t.length_m, t.width_m, t.desired_speed_mps, t.stride_m, float(mover.road_user), reach[0])
    state[0, MOTION : MOTION + 11] = _MOTION_ROWS[t.cls]
    set_leg(state, vu, 0, mover)
    return state, vu
