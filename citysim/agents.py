"""Agent kinds and the per-instant snapshot the renderer and metrics read.

The world (``citysim.world``) owns the pymunk bodies; each physics step it can
hand out immutable ``AgentState`` snapshots. Renderers and metrics read those
snapshots and never touch the physics.

Conventions: world frame of DESIGN.md (x along the street, y across, z up, m).
``heading_rad`` is the direction of motion in the ground plane, counter-clockwise
from +x. ``length_m`` is the extent along the heading (the paper's Table 1
"depth"), ``width_m`` across it, ``height_m`` up.
"""

from __future__ import annotations

from dataclasses import dataclass

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
