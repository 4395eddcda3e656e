"""Agent kinds (sizes, speeds, motion, drawing) and the per-instant snapshot.

The world (``citysim.world.physics``) owns the pymunk bodies; each physics step it can
hand out immutable ``AgentState`` snapshots. Renderers and metrics read those
snapshots and never touch the physics.

Conventions: world frame of DESIGN.md (x along the street, y across, z up, m).
``heading_rad`` is the direction of motion in the ground plane, counter-clockwise
from +x. ``length_m`` is the extent along the heading (the paper's Table 1
"depth"), ``width_m`` across it, ``height_m`` up.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: Classes the detector must light for (the paper's target group), plus noise.
TARGET_CLASSES = ("pedestrian", "group", "cyclist", "vehicle")
#: Classes the simulator can spawn that the detector must *not* light for.
NON_TARGET_CLASSES = ("animal",)


@dataclass(frozen=True)
class MemberState:
    """One pedestrian of a group, relative to the group's centre and heading."""

    forward_m: float  # offset along the group heading
    left_m: float  # offset to the left of the heading
    width_m: float
    height_m: float
    length_m: float  # step length (Table 1 depth)
    gait_phase_rad: float


@dataclass(frozen=True)
class AgentState:
    """Where one agent is and what it looks like at one instant."""

    object_id: int
    cls: str  # one of TARGET_CLASSES or NON_TARGET_CLASSES
    x_m: float  # centre of the ground footprint
    y_m: float
    heading_rad: float
    speed_mps: float
    length_m: float
    width_m: float
    height_m: float
    gait_phase_rad: float = 0.0  # leg swing (walkers, animals) or pedal crank (cyclists)
    members: tuple[MemberState, ...] = ()  # group members; empty for other classes
    light_on: bool = False  # headlights (vehicle, cyclist) or a flashlight (pedestrian)

    @property
    def is_target(self) -> bool:
        return self.cls in TARGET_CLASSES


# --------------------------------------------------------------------------
# Agent kinds: sizes (paper Table 1), speeds, motion parameters, drawing.
# --------------------------------------------------------------------------
KMH_PER_MPS = 3.6
#: No simulated agent is ever faster than this (the paper's street scenes).
MAX_SPEED_KMH = 60.0
MAX_SPEED_MPS = MAX_SPEED_KMH / KMH_PER_MPS


@dataclass(frozen=True)
class SpeedDistribution:
    """Desired (free-flow) speed of one agent, m/s.

    Uniform on [min_mps, max_mps], or, when ``mean_mps`` and ``std_mps`` are
    given, normal(mean, std) clipped to [min_mps, max_mps].
    """

    min_mps: float
    max_mps: float
    mean_mps: float | None = None
    std_mps: float | None = None

    def __post_init__(self) -> None:
        if not 0.0 < self.min_mps <= self.max_mps <= MAX_SPEED_MPS + 1e-9:
            raise ValueError(
                f"speed range must satisfy 0 < min <= max <= {MAX_SPEED_MPS:.2f} m/s "
                f"({MAX_SPEED_KMH:g} km/h), got min={self.min_mps} max={self.max_mps}"
            )

    def draw(self, rng: np.random.Generator) -> float:
        if self.mean_mps is not None and self.std_mps is not None:
            return float(
                np.clip(rng.normal(self.mean_mps, self.std_mps), self.min_mps, self.max_mps)
            )
        return float(rng.uniform(self.min_mps, self.max_mps))


@dataclass(frozen=True)
class MotionParams:
    """How an agent of one kind moves (the world's behaviour model reads these).

    Longitudinal control is the Intelligent Driver Model (Treiber et al. 2000):
    ``accel_mps2`` (a), ``comfort_decel_mps2`` (b), ``headway_s`` (T),
    ``min_gap_m`` (s0); ``max_decel_mps2`` bounds braking. Lateral control picks
    an offset within the path's band: ``lateral_speed_mps`` bounds sidestepping,
    ``lateral_margin_m`` is the clearance kept to others when passing, and
    ``horizon_s`` the look-ahead time used to score free space. ``yaw_rate_rps``
    bounds how fast the body turns toward its direction of motion; ``max_tilt_rad``
    how far it turns away from its path's direction while swerving (walkers and
    animals sidestep facing forward: 0).
    """

    accel_mps2: float
    comfort_decel_mps2: float
    max_decel_mps2: float
    headway_s: float
    min_gap_m: float
    lookahead_m: float
    lateral_speed_mps: float
    lateral_margin_m: float
    horizon_s: float
    yaw_rate_rps: float
    max_tilt_rad: float = 0.0


@dataclass(frozen=True)
class DrawOptions:
    """Per-scenario knobs for drawing one agent (from ``config`` traffic specs)."""

    speed: SpeedDistribution | None = None  # None: the kind's default
    running_fraction: float = 0.0  # walkers: share that run
    running_speed: SpeedDistribution | None = None
    light_fraction: float = 0.0  # flashlight (walkers) or headlight (cyclists, vehicles)
    night: bool = True  # lights are only switched on at night
    group_size: tuple[int, int] = (2, 4)
    max_group_width_m: float = 3.0  # the path's room: wider groups walk in two rows


@dataclass(frozen=True)
class AgentTraits:
    """What one agent looks like and how fast it wants to go; no position.

    ``stride_m`` is the distance covered per full gait (or crank, or wheel)
    cycle: the world advances ``gait_phase_rad`` by 2 pi per ``stride_m``.
    ``members`` are a group's pedestrians with their initial gait phases.
    """

    cls: str
    width_m: float
    height_m: float
    length_m: float
    desired_speed_mps: float
    stride_m: float
    light_on: bool = False
    running: bool = False
    gait_phase_rad: float = 0.0
    members: tuple[MemberState, ...] = ()


@dataclass(frozen=True)
class AgentKind:
    """One class of agent: Table 1 size ranges (m), default speed and motion."""

    cls: str
    width_m: tuple[float, float]
    height_m: tuple[float, float]
    length_m: tuple[float, float]
    speed: SpeedDistribution
    motion: MotionParams
    draw: Callable[[AgentKind, np.random.Generator, DrawOptions], AgentTraits]


def _uniform(rng: np.random.Generator, lo_hi: tuple[float, float]) -> float:
    return float(rng.uniform(lo_hi[0], lo_hi[1]))


def _draw_pedestrian(kind: AgentKind, rng: np.random.Generator, opt: DrawOptions) -> AgentTraits:
    width, height, step = (
        _uniform(rng, kind.width_m),
        _uniform(rng, kind.height_m),
        _uniform(rng, kind.length_m),
    )
    running = bool(rng.random() < opt.running_fraction)
    speed = (opt.running_speed or RUNNING_SPEED) if running else (opt.speed or kind.speed)
    return AgentTraits(
        cls=kind.cls,
        width_m=width,
        height_m=height,
        length_m=step,
        desired_speed_mps=speed.draw(rng),
        # the paper's depth is one step; a gait cycle is two steps
        stride_m=2.0 * step,
        light_on=opt.night and bool(rng.random() < opt.light_fraction),
        running=running,
        gait_phase_rad=float(rng.uniform(0.0, 2.0 * math.pi)),
    )


#: Least clearance between neighbours walking side by side, m.
GROUP_MIN_GAP_M = 0.1
#: Distance between the rows of a group that is too wide for its path, m.
GROUP_ROW_SPACING_M = 0.9


def _draw_group(kind: AgentKind, rng: np.random.Generator, opt: DrawOptions) -> AgentTraits:
    """2-4 pedestrians side by side; in rows when the path is too narrow.

    Members are drawn from the pedestrian ranges; the tallest is redrawn into the
    group's height range (Table 1: 1.5-2 m). Side by side, the formation width is
    drawn in the group's width range (Table 1: 1.2-3 m) as far as the path's room
    (``opt.max_group_width_m``) allows; otherwise members walk in rows with the
    least gap. The footprint (width_m x length_m) is symmetric about the centre.
    """
    ped = AGENT_KINDS["pedestrian"]
    n = int(rng.integers(opt.group_size[0], opt.group_size[1] + 1))
    widths = rng.uniform(*ped.width_m, size=n)
    heights = rng.uniform(*ped.height_m, size=n)
    heights[int(np.argmax(heights))] = _uniform(rng, kind.height_m)
    steps = rng.uniform(*kind.length_m, size=n)
    phases = rng.uniform(0.0, 2.0 * math.pi, size=n)
    narrowest = widths.sum() + GROUP_MIN_GAP_M * (n - 1)
    lo, hi = max(kind.width_m[0], narrowest), min(kind.width_m[1], opt.max_group_width_m)
    if lo <= hi:
        rows = [list(range(n))]
        gap = (_uniform(rng, (lo, hi)) - widths.sum()) / (n - 1)
    else:
        gap = GROUP_MIN_GAP_M
        per_row = n
        while (
            per_row > 1
            and max(
                widths[i : i + per_row].sum() + gap * (len(widths[i : i + per_row]) - 1)
                for i in range(0, n, per_row)
            )
            > opt.max_group_width_m
        ):
            per_row -= 1
        per_row = math.ceil(n / math.ceil(n / per_row))  # balance the rows: 2+2, not 3+1
        rows = [list(range(i, min(i + per_row, n))) for i in range(0, n, per_row)]
    members = []
    for r, row in enumerate(rows):
        forward = GROUP_ROW_SPACING_M * ((len(rows) - 1) / 2 - r)
        left = (widths[row].sum() + gap * (len(row) - 1)) / 2  # rows are centred
        for i in row:
            members.append(
                MemberState(
                    forward_m=float(forward),
                    left_m=float(left - widths[i] / 2),
                    width_m=float(widths[i]),
                    height_m=float(heights[i]),
                    length_m=float(steps[i]),
                    gait_phase_rad=float(phases[i]),
                )
            )
            left -= widths[i] + gap
    width = 2.0 * max(abs(m.left_m) + m.width_m / 2 for m in members)
    length = 2.0 * max(abs(m.forward_m) + m.length_m / 2 for m in members)
    return AgentTraits(
        cls=kind.cls,
        width_m=float(width),
        height_m=float(heights.max()),
        length_m=float(length),
        desired_speed_mps=(opt.speed or kind.speed).draw(rng),
        stride_m=2.0 * float(steps.mean()),
        light_on=opt.night and bool(rng.random() < opt.light_fraction),
        members=tuple(members),
    )


def _draw_rigid(stride_m: tuple[float, float]):
    """Draw a cyclist / vehicle / animal: Table 1 box, speed, lights."""

    def draw(kind: AgentKind, rng: np.random.Generator, opt: DrawOptions) -> AgentTraits:
        return AgentTraits(
            cls=kind.cls,
            width_m=_uniform(rng, kind.width_m),
            height_m=_uniform(rng, kind.height_m),
            length_m=_uniform(rng, kind.length_m),
            desired_speed_mps=(opt.speed or kind.speed).draw(rng),
            stride_m=_uniform(rng, stride_m),
            light_on=opt.night and bool(rng.random() < opt.light_fraction),
            gait_phase_rad=float(rng.uniform(0.0, 2.0 * math.pi)),
        )

    return draw


WALK_SPEED = SpeedDistribution(1.0, 1.8)
RUNNING_SPEED = SpeedDistribution(2.5, 4.0)

_WALKER_MOTION = MotionParams(
    accel_mps2=1.0,
    comfort_decel_mps2=1.5,
    max_decel_mps2=4.0,
    headway_s=0.6,
    min_gap_m=0.35,
    lookahead_m=12.0,
    lateral_speed_mps=0.6,
    lateral_margin_m=0.12,
    horizon_s=3.0,
    yaw_rate_rps=4.0,
)

#: The agent kinds by class name. Sizes: paper Table 1 (animals: fox/dog size,
#: not in the paper). Speeds: walking 1.0-1.8 m/s (running 2.5-4), cycling
#: 3-8 m/s, driving 30-60 km/h on a residential street.
AGENT_KINDS: dict[str, AgentKind] = {
    "pedestrian": AgentKind(
        "pedestrian",
        (0.3, 0.64),
        (1.15, 2.0),
        (0.3, 0.79),
        WALK_SPEED,
        _WALKER_MOTION,
        _draw_pedestrian,
    ),
    "group": AgentKind(
        "group",
        (1.2, 3.0),
        (1.5, 2.0),
        (0.3, 0.79),
        SpeedDistribution(1.0, 1.6),
        _WALKER_MOTION,
        _draw_group,
    ),
    "cyclist": AgentKind(
        "cyclist",
        (0.3, 0.64),
        (1.5, 1.9),
        (1.5, 1.7),
        SpeedDistribution(3.0, 8.0),
        MotionParams(
            accel_mps2=1.0,
            comfort_decel_mps2=2.0,
            max_decel_mps2=5.0,
            headway_s=1.0,
            min_gap_m=1.0,
            lookahead_m=40.0,
            lateral_speed_mps=0.8,
            lateral_margin_m=0.25,
            horizon_s=4.0,
            yaw_rate_rps=2.0,
            max_tilt_rad=0.3,
        ),
        # distance per crank turn: ~2.1 m wheel circumference x gear ratio 2-3
        _draw_rigid((4.5, 6.5)),
    ),
    "vehicle": AgentKind(
        "vehicle",
        (1.4, 1.8),
        (1.4, 2.0),
        (3.7, 4.6),
        SpeedDistribution(30.0 / KMH_PER_MPS, 60.0 / KMH_PER_MPS),
        MotionParams(
            accel_mps2=1.5,
            comfort_decel_mps2=2.5,
            max_decel_mps2=8.0,
            headway_s=1.2,
            min_gap_m=2.0,
            lookahead_m=90.0,
            lateral_speed_mps=0.8,
            lateral_margin_m=0.5,
            horizon_s=4.0,
            yaw_rate_rps=1.0,
            max_tilt_rad=0.1,
        ),
        # wheel circumference: the phase is the wheel's turn
        _draw_rigid((1.9, 2.1)),
    ),
    "animal": AgentKind(
        "animal",
        (0.2, 0.35),
        (0.3, 0.7),
        (0.5, 1.0),
        SpeedDistribution(0.5, 2.5),
        MotionParams(
            accel_mps2=2.0,
            comfort_decel_mps2=3.0,
            max_decel_mps2=6.0,
            headway_s=0.4,
            min_gap_m=0.3,
            lookahead_m=8.0,
            lateral_speed_mps=0.6,
            lateral_margin_m=0.1,
            horizon_s=2.0,
            yaw_rate_rps=4.0,
        ),
        _draw_rigid((0.6, 1.0)),
    ),
}


def draw_agent(
    cls: str, rng: np.random.Generator, options: DrawOptions = DrawOptions()
) -> AgentTraits:
    """Draw the looks and desired speed of one agent of class ``cls``."""
    try:
        kind = AGENT_KINDS[cls]
    except KeyError:
        raise ValueError(f"unknown agent class {cls!r}; valid: {', '.join(AGENT_KINDS)}") from None
    return kind.draw(kind, rng, options)
