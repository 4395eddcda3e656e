"""Drawing an agent's looks from its kind's record, and the per-instant snapshot.

The kinds are data (``citysim.config.kinds.AGENT_KINDS``); each names a body recipe of
``BODY_RECIPES`` here ("walker", "group", "rigid") that draws one agent's ``AgentTraits``.
The world (``citysim.world.physics``) owns the pymunk bodies; each physics step it can
hand out immutable ``AgentState`` snapshots. Renderers and metrics read those
snapshots and never touch the physics.

Conventions: world frame of docs/design/architecture.md (x along the street, y across, z up, m).
``heading_rad`` is the direction of motion in the ground plane, counter-clockwise
from +x. ``length_m`` is the extent along the heading (the paper's Table 1
"depth"), ``width_m`` across it, ``height_m`` up.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from citysim.config.kinds import TARGET_KINDS, AgentKind, kind_of
from citysim.config.motion import DrawOptions

# A frozen dataclass's __init__ sets its fields one object.__setattr__ at a time (about twice the
# time of this way, measured): the world and the replay, which hand out every agent's snapshot each
# step, build them with all fields at once, the same objects (tests/citysim/sim/test_replay.py and
# tests/citysim/world/test_compiled.py compare them with constructor-made ones)
_new_object = object.__new__
_set_attribute = object.__setattr__


def frozen_from_fields(cls: type, fields: dict):
    """An instance of the frozen dataclass ``cls`` of ``fields`` (name -> value, every field in field
    order), as ``cls(**fields)`` makes it."""
    obj = _new_object(cls)
    _set_attribute(obj, "__dict__", fields)
    return obj


@dataclass(frozen=True)
class MemberState:
    """One pedestrian of a group, relative to the group's centre and heading."""

    forward_m: float  # offset along the group heading
    left_m: float  # offset to the left of the heading
    width_m: float
    height_m: float
    length_m: float  # step length (Table 1 depth)
    gait_phase_rad: float


#: ``TARGET_KINDS`` as a set
_TARGET_KINDS = frozenset(TARGET_KINDS)


@dataclass(frozen=True)
class AgentState:
    """Where one agent is and what it looks like at one instant."""

    object_id: int
    cls: str  # a kind of citysim.config.kinds.AGENT_KINDS
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
        # a set look-up: asked of every agent every step (the zone and false-on-time counters)
        return self.cls in _TARGET_KINDS


@dataclass(frozen=True)
class AgentColumns:
    """The agents of many steps as columns, one row per agent and step (``AgentState``'s fields of
    the same names; contiguous arrays): what a numpy pass over a run of steps reads at once
    (``citysim.sim.replay`` hands out a chunk of recorded steps so)."""

    x_m: np.ndarray  # float64
    y_m: np.ndarray
    heading_rad: np.ndarray
    speed_mps: np.ndarray
    cls: tuple[str, ...]
    light_on: np.ndarray  # bool


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


def _uniform(rng: np.random.Generator, lo_hi: tuple[float, float]) -> float:
    return float(rng.uniform(lo_hi[0], lo_hi[1]))


def _draw_pedestrian(kind: AgentKind, rng: np.random.Generator, opt: DrawOptions) -> AgentTraits:
    width, height, step = (
        _uniform(rng, kind.width_m),
        _uniform(rng, kind.height_m),
        _uniform(rng, kind.length_m),
    )
    running = bool(rng.random() < opt.running_fraction)
    run_speed = opt.running_speed or kind.running_speed
    speed = run_speed if running and run_speed is not None else (opt.speed or kind.speed)
    return AgentTraits(
        cls=kind.name,
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
    ped = kind_of(kind.body.member or "pedestrian")
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
        cls=kind.name,
        width_m=float(width),
        height_m=float(heights.max()),
        length_m=float(length),
        desired_speed_mps=(opt.speed or kind.speed).draw(rng),
        stride_m=2.0 * float(steps.mean()),
        light_on=opt.night and bool(rng.random() < opt.light_fraction),
        members=tuple(members),
    )


def _draw_rigid(kind: AgentKind, rng: np.random.Generator, opt: DrawOptions) -> AgentTraits:
    """A rider, vehicle or animal: a box in its kind's ranges, speed, lights; its gait (crank,
    wheel or legs) advances one cycle per ``kind.body.stride_m``."""
    if kind.body.stride_m is None:
        raise ValueError(f"kind {kind.name!r}: a 'rigid' body needs a stride_m range")
    return AgentTraits(
        cls=kind.name,
        width_m=_uniform(rng, kind.width_m),
        height_m=_uniform(rng, kind.height_m),
        length_m=_uniform(rng, kind.length_m),
        desired_speed_mps=(opt.speed or kind.speed).draw(rng),
        stride_m=_uniform(rng, kind.body.stride_m),
        light_on=opt.night and bool(rng.random() < opt.light_fraction),
        gait_phase_rad=float(rng.uniform(0.0, 2.0 * math.pi)),
    )


BodyRecipe = Callable[[AgentKind, np.random.Generator, DrawOptions], AgentTraits]

#: Body recipes by name (``AgentKind.body.recipe``): (kind, rng, options) -> traits.
BODY_RECIPES: dict[str, BodyRecipe] = {
    "walker": _draw_pedestrian,
    "group": _draw_group,
    "rigid": _draw_rigid,
}


_DEFAULT_OPTIONS = DrawOptions()


def draw_agent(
    cls: str, rng: np.random.Generator, options: DrawOptions = _DEFAULT_OPTIONS
) -> AgentTraits:
    """Draw the looks and desired speed of one agent of class ``cls``."""
    kind = kind_of(cls)
    try:
        recipe = BODY_RECIPES[kind.body.recipe]
    except KeyError:
        raise ValueError(
            f"kind {cls!r}: unknown body recipe {kind.body.recipe!r}; valid: {', '.join(BODY_RECIPES)}"
        ) from None
    return recipe(kind, rng, options)
