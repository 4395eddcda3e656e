"""The road-user kinds as data: one frozen ``AgentKind`` record per kind, in ``AGENT_KINDS``.

Every per-kind fact lives here: whether the lamps must light for it and how the detector's
metrics score it, whether it rides the lanes, its sizes, speeds and motion, how its looks are
drawn (a body recipe by name, ``citysim.world.agents``), how it moves through the street (a
route planner by name, ``citysim.world.traffic``), the light it carries, how the networked
controller and the zone metrics treat it, its plot colour. The traffic schema
(``citysim.config.traffic``) derives one spec class per kind from these records.

A new kind is one record appended to ``AGENT_KINDS`` plus its 3D shape
(``citysim.render.models``). Append, never insert: the order of ``AGENT_KINDS`` is the
order in which the kinds' arrival processes get their random streams, so a kind inserted
before others would reshuffle their traffic.
"""

from __future__ import annotations

from dataclasses import dataclass

from citysim.config.motion import MotionParams, SpeedDistribution
from detector.classes import CLASSES, TABLE1, SizeRange

__all__ = [
    "AGENT_KINDS",
    "DETECTOR_CLASSES",
    "TABLE1_SIZES_M",
    "AgentKind",
    "Body",
    "Pauses",
    "Sizes",
    "TARGET_KINDS",
    "kind_of",
]

#: The detector's classes, in its order: what a kind is scored as in the confusion metrics and
#: what the detector reports to the controllers (the detector owns them).
DETECTOR_CLASSES = CLASSES

#: Ranges an agent's box is drawn from, (min, max) m; ``length_m`` along the heading.
Sizes = SizeRange

#: paper Table 1: width x height x depth of the detector's target classes, m: the detector's
#: own table (``detector.classes.TABLE1``), the one copy of these numbers.
TABLE1_SIZES_M = {name: TABLE1[name] for name in CLASSES[1:]}


@dataclass(frozen=True)
class Body:
    """How an agent's looks are drawn: ``recipe`` names a body recipe of
    ``citysim.world.agents.BODY_RECIPES`` ("walker", "group", "rigid"); ``stride_m`` is the
    range of distance per gait, crank or wheel cycle ("rigid"); ``member`` the kind a group's
    members are drawn as ("group")."""

    recipe: str
    stride_m: tuple[float, float] | None = None
    member: str | None = None


@dataclass(frozen=True)
class Pauses:
    """Stops now and then while moving: on average one per ``every_s`` seconds on the move,
    each lasting uniformly ``duration_s`` seconds."""

    every_s: float
    duration_s: tuple[float, float]


@dataclass(frozen=True, kw_only=True)
class AgentKind:
    """Everything the simulator knows about one kind of road user (or non-target animal).

    ``is_target``: the lamps must light for it (the detector's target group).
    ``detector_class``: which of ``DETECTOR_CLASSES`` it is scored as in the confusion
    metrics ("noise" for non-targets). ``road_user``: it rides the lanes (walkers give way to
    it when crossing; a scripted one keeps a lane), not the sidewalks. ``route``: its planner
    in ``citysim.world.traffic.ROUTE_PLANNERS``. ``spec``: the traffic spec it is configured
    by in scenarios ("pedestrian", "group", "walker", "lit", "plain"; ``citysim.config.traffic``).
    ``shape``: its 3D model in ``citysim.render.models.AGENT_MODELS``. ``beam``: the light it
    carries when lit (``citysim.render.beams.BEAMS``; None: its light is never drawn), and
    ``lit_share`` the default share lit at night (flashlights, headlights). A scripted agent
    of the kind is lit at night when most of its kind are (``lit_share >= 0.5``).
    ``crossing_share``: default share of walkers that cross the road. ``running_share`` and
    ``running_speed``: walkers that run. ``hold_factor`` and ``lamps_ahead``: how long and how
    many lamps ahead the networked controller lights when the detector reports this class
    (they apply to kinds that are a detector class: the detector reports classes, not kinds).
    ``lookahead_s``: how far ahead of itself it needs the road lit (zone metrics).
    ``colour``: in plots. ``pauses``: stops on the way (animals sniffing).
    """

    name: str
    is_target: bool
    detector_class: str
    road_user: bool
    sizes: Sizes
    speed: SpeedDistribution
    motion: MotionParams
    body: Body
    route: str
    spec: str
    shape: str
    beam: str | None = None
    lit_share: float = 0.0
    crossing_share: float = 0.0
    running_share: float = 0.0
    running_speed: SpeedDistribution | None = None
    hold_factor: float = 1.0
    lamps_ahead: int = 1
    lookahead_s: float = 0.0
    colour: str | None = None
    pauses: Pauses | None = None

    def __post_init__(self) -> None:
        if self.detector_class not in DETECTOR_CLASSES:
            raise ValueError(
                f"kind {self.name!r}: detector_class must be one of {DETECTOR_CLASSES}, "
                f"got {self.detector_class!r}"
            )
        if self.is_target == (self.detector_class == "noise"):
            raise ValueError(
                f"kind {self.name!r}: a target is scored as a target class, a non-target as "
                f"noise; got is_target={self.is_target}, detector_class={self.detector_class!r}"
            )
        if self.is_target and self.colour is None:
            raise ValueError(f"kind {self.name!r}: a target kind needs a plot colour")
        for share in (self.lit_share, self.crossing_share, self.running_share):
            if not 0.0 <= share <= 1.0:
                raise ValueError(f"kind {self.name!r}: shares lie within 0..1, got {share}")

    @property
    def width_m(self) -> tuple[float, float]:
        return self.sizes.width_m

    @property
    def height_m(self) -> tuple[float, float]:
        return self.sizes.height_m

    @property
    def length_m(self) -> tuple[float, float]:
        return self.sizes.length_m


_WALKER_MOTION = MotionParams(
    accel_mps2=1.0, comfort_decel_mps2=1.5, max_decel_mps2=4.0, headway_s=0.6, min_gap_m=0.35,
    lookahead_m=12.0, lateral_speed_mps=0.6, lateral_margin_m=0.12, horizon_s=3.0,
    yaw_rate_rps=4.0,
)  # fmt: skip
_RIDER_MOTION = MotionParams(
    accel_mps2=1.0, comfort_decel_mps2=2.0, max_decel_mps2=5.0, headway_s=1.0, min_gap_m=1.0,
    lookahead_m=40.0, lateral_speed_mps=0.8, lateral_margin_m=0.25, horizon_s=4.0,
    yaw_rate_rps=2.0, max_tilt_rad=0.3,
)  # fmt: skip
_DRIVER_MOTION = MotionParams(
    accel_mps2=1.5, comfort_decel_mps2=2.5, max_decel_mps2=8.0, headway_s=1.2, min_gap_m=2.0,
    lookahead_m=90.0, lateral_speed_mps=0.8, lateral_margin_m=0.5, horizon_s=4.0,
    yaw_rate_rps=1.0, max_tilt_rad=0.1,
)  # fmt: skip
_ANIMAL_MOTION = MotionParams(
    accel_mps2=2.0, comfort_decel_mps2=3.0, max_decel_mps2=6.0, headway_s=0.4, min_gap_m=0.3,
    lookahead_m=8.0, lateral_speed_mps=0.6, lateral_margin_m=0.1, horizon_s=2.0,
    yaw_rate_rps=4.0,
)  # fmt: skip

#: The kinds by name, in the order of their random streams (append new kinds at the end).
#: Speeds: walking 1.0-1.8 m/s (running 2.5-4), cycling 3-8 m/s, driving 30-60 km/h on a
#: residential street. Animals (fox/dog size) and e-scooters are not in the paper's Table 1.
AGENT_KINDS: dict[str, AgentKind] = {
    k.name: k
    for k in (
        AgentKind(
            name="pedestrian", is_target=True, detector_class="pedestrian", road_user=False,
            sizes=TABLE1_SIZES_M["pedestrian"], speed=SpeedDistribution(1.0, 1.8),
            motion=_WALKER_MOTION,
            # the paper's depth is one step; a gait cycle is two (the recipe doubles it)
            body=Body("walker"), route="sidewalk", spec="pedestrian", shape="pedestrian",
            beam="flashlight", lit_share=0.05, crossing_share=0.3,
            running_share=0.05, running_speed=SpeedDistribution(2.5, 4.0),
            lamps_ahead=1, colour="#1f77b4",
        ),
        AgentKind(
            name="group", is_target=True, detector_class="group", road_user=False,
            sizes=TABLE1_SIZES_M["group"], speed=SpeedDistribution(1.0, 1.6),
            motion=_WALKER_MOTION,
            body=Body("group", member="pedestrian"), route="sidewalk", spec="group",
            shape="group",
            # a group's flashlight is drawn (lit_share) but has no beam: it is never rendered
            beam=None, lit_share=0.1, crossing_share=0.2, lamps_ahead=1, colour="#9467bd",
        ),
        AgentKind(
            name="cyclist", is_target=True, detector_class="cyclist", road_user=True,
            sizes=TABLE1_SIZES_M["cyclist"], speed=SpeedDistribution(3.0, 8.0),
            motion=_RIDER_MOTION,
            # distance per crank turn: ~2.1 m wheel circumference x gear ratio 2-3
            body=Body("rigid", stride_m=(4.5, 6.5)), route="road_edge", spec="lit",
            shape="cyclist", beam="bike_lamp", lit_share=0.8, lamps_ahead=2, colour="#2ca02c",
        ),
        AgentKind(
            name="vehicle", is_target=True, detector_class="vehicle", road_user=True,
            sizes=TABLE1_SIZES_M["vehicle"], speed=SpeedDistribution.kmh(30.0, 60.0),
            motion=_DRIVER_MOTION,
            # wheel circumference: the phase is the wheel's turn
            body=Body("rigid", stride_m=(1.9, 2.1)), route="lane", spec="lit", shape="vehicle",
            # a car is through a 30 m lamp zone in ~2 s: the lamps ahead hold half as long
            beam="headlights", lit_share=1.0, hold_factor=0.5, lamps_ahead=4,
            colour="#d62728",
        ),
        AgentKind(
            name="animal", is_target=False, detector_class="noise", road_user=False,
            sizes=Sizes((0.2, 0.35), (0.3, 0.7), (0.5, 1.0)), speed=SpeedDistribution(0.5, 2.5),
            motion=_ANIMAL_MOTION,
            body=Body("rigid", stride_m=(0.6, 1.0)), route="verge_wander", spec="plain",
            # foxes and dogs stop now and then (every ~10 s of walking, for 1-4 s)
            shape="animal", pauses=Pauses(every_s=10.0, duration_s=(1.0, 4.0)),
        ),
        AgentKind(
            # a rider standing on a low deck, holding the handlebar of a steering column
            name="e_scooter", is_target=True,
            # The detector has no scooter class. An e-scooter is a rider on small wheels in the
            # road at cycling speeds, so the lamps should answer it as they answer a cyclist
            # (lamps ahead, hold): calling it a cyclist counts as right.
            detector_class="cyclist", road_user=True,
            sizes=Sizes(width_m=(0.4, 0.6), height_m=(1.6, 2.0), length_m=(1.0, 1.2)),
            speed=SpeedDistribution.kmh(15.0, 25.0),
            motion=_RIDER_MOTION,  # it brakes and swerves like a bicycle
            # wheel circumference of a ~0.22 m (8.5-10 inch) wheel: the phase is the wheel's turn
            body=Body("rigid", stride_m=(0.6, 0.8)), route="road_edge", spec="lit",
            shape="e_scooter", beam="bike_lamp", lit_share=0.8, lamps_ahead=2, colour="#ff7f0e",
        ),
    )
}  # fmt: skip

#: Kinds the lamps must light for, in registry order.
TARGET_KINDS = tuple(k.name for k in AGENT_KINDS.values() if k.is_target)


def kind_of(name: str) -> AgentKind:
    """The record of kind ``name``; ValueError naming the valid kinds if there is none."""
    try:
        return AGENT_KINDS[name]
    except KeyError:
        raise ValueError(f"unknown agent class {name!r}; valid: {', '.join(AGENT_KINDS)}") from None
