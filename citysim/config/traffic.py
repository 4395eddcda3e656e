"""Scenario schema for traffic: per-class arrival rates, hourly profiles, speeds, behaviour shares.

Arrivals of each class are a Poisson process whose rate is ``rate_per_hour``
times the hourly profile: ``hourly_profile[k]`` multiplies the rate during hour
k of the run (hour 0 starts at the scenario's ``start_hour``); past the end of
the list the last multiplier holds. Speeds are desired (free-flow) speeds,
given in km/h or m/s; nothing moves faster than 60 km/h.

One spec class per kind of ``citysim.config.kinds.AGENT_KINDS``, derived from its record:
the record names which spec it is configured by ("plain", "lit", "walker", "pedestrian",
"group") and supplies the defaults (share lit at night, share crossing, share running), so
a new kind needs no field written here. ``TrafficClasses`` has one field per kind.
"""

from __future__ import annotations

from typing import Any, ClassVar, Literal

from pydantic import Field, create_model, model_validator

from citysim.config.base import FieldPathError, Spec
from citysim.config.kinds import AGENT_KINDS, DETECTOR_CLASSES, TARGET_KINDS, AgentKind
from citysim.config.motion import (
    KMH_PER_MPS,
    MAX_SPEED_KMH,
    MAX_SPEED_MPS,
    DrawOptions,
    SpeedDistribution,
)


class _SpeedRange(Spec):
    """Uniform on [min, max], or normal(mean, std) clipped to [min, max]."""

    UNIT_TO_MPS: ClassVar[float] = 1.0
    min: float
    max: float
    mean: float | None = None
    std: float | None = Field(default=None, ge=0)

    @model_validator(mode="after")
    def _order(self) -> _SpeedRange:
        if self.min > self.max:
            raise FieldPathError(("max",), f"must be >= min ({self.min:g}), got {self.max:g}")
        if (self.mean is None) != (self.std is None):
            raise FieldPathError(
                ("std" if self.std is None else "mean",), "give both mean and std, or neither"
            )
        if self.mean is not None and not self.min <= self.mean <= self.max:
            raise FieldPathError(
                ("mean",),
                f"must lie within min..max ({self.min:g}..{self.max:g}), got {self.mean:g}",
            )
        return self

    def distribution(self) -> SpeedDistribution:
        k = self.UNIT_TO_MPS
        return SpeedDistribution(
            self.min * k,
            min(self.max * k, MAX_SPEED_MPS),
            None if self.mean is None else self.mean * k,
            None if self.std is None else self.std * k,
        )


class SpeedKmh(_SpeedRange):
    UNIT_TO_MPS: ClassVar[float] = 1.0 / KMH_PER_MPS
    min: float = Field(gt=0, le=MAX_SPEED_KMH)
    max: float = Field(gt=0, le=MAX_SPEED_KMH)


class SpeedMps(_SpeedRange):
    min: float = Field(gt=0, le=round(MAX_SPEED_MPS, 4))
    max: float = Field(gt=0, le=round(MAX_SPEED_MPS, 4))


class TrafficClassSpec(Spec):
    """Arrivals and speeds of one agent class ("plain" spec); ``kind`` names the class.

    ``FROM_KIND`` maps a field to the ``AgentKind`` attribute that gives its default (a
    share, 0..1) in the class made for each kind.
    """

    kind: ClassVar[str] = ""
    FROM_KIND: ClassVar[dict[str, str]] = {}
    rate_per_hour: float = Field(default=0.0, ge=0, le=20000, description="mean arrivals per hour")
    hourly_profile: tuple[float, ...] = Field(
        default=(), description="rate multiplier per hour of the run"
    )
    speed_kmh: SpeedKmh | None = None
    speed_mps: SpeedMps | None = None

    @model_validator(mode="after")
    def _one_speed(self) -> TrafficClassSpec:
        if self.speed_kmh is not None and self.speed_mps is not None:
            raise FieldPathError(("speed_mps",), "give either speed_kmh or speed_mps, not both")
        for i, m in enumerate(self.hourly_profile):
            if not 0 <= m <= 100:
                raise FieldPathError(
                    ("hourly_profile", i), f"multipliers must lie within 0..100, got {m:g}"
                )
        return self

    def rate_per_s(self, t_s: float) -> float:
        """Arrival rate at ``t_s`` seconds into the run, 1/s."""
        m = 1.0
        if self.hourly_profile:
            m = self.hourly_profile[min(int(t_s // 3600.0), len(self.hourly_profile) - 1)]
        return self.rate_per_hour * m / 3600.0

    @property
    def max_rate_per_s(self) -> float:
        return self.rate_per_hour * max(self.hourly_profile, default=1.0) / 3600.0

    def speed(self) -> SpeedDistribution:
        chosen = self.speed_kmh or self.speed_mps
        return chosen.distribution() if chosen is not None else AGENT_KINDS[self.kind].speed

    def draw_options(self, *, night: bool, max_group_width_m: float = 3.0) -> DrawOptions:
        return DrawOptions(speed=self.speed(), night=night, max_group_width_m=max_group_width_m)


class WalkerTraffic(TrafficClassSpec):
    """Walkers on the sidewalks: some cross the road, some carry a flashlight."""

    FROM_KIND: ClassVar[dict[str, str]] = {
        "crossing_fraction": "crossing_share",
        "flashlight_fraction": "lit_share",
    }
    crossing_fraction: float = Field(
        default=0.3, ge=0, le=1, description="share that crosses the street"
    )
    marked_crossing_fraction: float = Field(
        default=0.6,
        ge=0,
        le=1,
        description="share of crossers using street.crossings_x_m; the rest cross anywhere",
    )
    flashlight_fraction: float = Field(
        default=0.05, ge=0, le=1, description="share carrying a lit flashlight at night"
    )

    def draw_options(self, *, night: bool, max_group_width_m: float = 3.0) -> DrawOptions:
        return DrawOptions(
            speed=self.speed(), light_fraction=self.flashlight_fraction, night=night,
            max_group_width_m=max_group_width_m,
        )  # fmt: skip


class PedestrianTrafficSpec(WalkerTraffic):
    """Walkers alone, some of them running."""

    FROM_KIND: ClassVar[dict[str, str]] = {
        **WalkerTraffic.FROM_KIND,
        "running_fraction": "running_share",
    }
    running_fraction: float = Field(default=0.05, ge=0, le=1, description="share that runs")
    running_speed_mps: SpeedMps | None = None

    def draw_options(self, *, night: bool, max_group_width_m: float = 3.0) -> DrawOptions:
        run = self.running_speed_mps.distribution() if self.running_speed_mps else None
        return DrawOptions(
            speed=self.speed(), running_fraction=self.running_fraction, running_speed=run,
            light_fraction=self.flashlight_fraction, night=night,
        )  # fmt: skip


class GroupSize(Spec):
    min: int = Field(default=2, ge=2, le=4)
    max: int = Field(default=4, ge=2, le=4)

    @model_validator(mode="after")
    def _order(self) -> GroupSize:
        if self.min > self.max:
            raise FieldPathError(("max",), f"must be >= min ({self.min}), got {self.max}")
        return self


class GroupTrafficSpec(WalkerTraffic):
    """Walkers side by side, 2-4 of them."""

    size: GroupSize = GroupSize()

    def draw_options(self, *, night: bool, max_group_width_m: float = 3.0) -> DrawOptions:
        return DrawOptions(
            speed=self.speed(), light_fraction=self.flashlight_fraction, night=night,
            group_size=(self.size.min, self.size.max), max_group_width_m=max_group_width_m,
        )  # fmt: skip


class LitTraffic(TrafficClassSpec):
    """Riders and drivers: a share rides or drives with lights on at night."""

    FROM_KIND: ClassVar[dict[str, str]] = {"lights_fraction": "lit_share"}
    lights_fraction: float = Field(
        default=1.0, ge=0, le=1, description="share riding/driving with lights on at night"
    )

    def draw_options(self, *, night: bool, max_group_width_m: float = 3.0) -> DrawOptions:
        return DrawOptions(speed=self.speed(), light_fraction=self.lights_fraction, night=night)


#: The spec a kind is configured by (``AgentKind.spec``) -> its base class.
SPEC_BASES: dict[str, type[TrafficClassSpec]] = {
    "plain": TrafficClassSpec,
    "lit": LitTraffic,
    "walker": WalkerTraffic,
    "pedestrian": PedestrianTrafficSpec,
    "group": GroupTrafficSpec,
}


def _spec_class(kind: AgentKind) -> type[TrafficClassSpec]:
    """The traffic spec class of one kind: its record's spec, with the record's defaults."""
    try:
        base = SPEC_BASES[kind.spec]
    except KeyError:
        raise ValueError(
            f"kind {kind.name!r}: spec must be one of {', '.join(SPEC_BASES)}, got {kind.spec!r}"
        ) from None
    if kind.route == "sidewalk" and not issubclass(base, WalkerTraffic):
        raise ValueError(f"kind {kind.name!r}: walkers (route 'sidewalk') need a walker spec")
    defaults: dict[str, Any] = {
        field: (float, Field(default=getattr(kind, attr), ge=0, le=1,
                             description=base.model_fields[field].description))
        for field, attr in base.FROM_KIND.items()
    }  # fmt: skip
    title = "".join(part.capitalize() for part in kind.name.split("_"))
    spec = create_model(
        f"{title}Traffic", __base__=base, __module__=__name__,
        __doc__=f"Arrivals, speeds and shares of kind {kind.name!r}.", **defaults,
    )  # fmt: skip
    spec.kind = kind.name
    return spec


#: Traffic spec class of each kind, in registry order.
TRAFFIC_SPECS: dict[str, type[TrafficClassSpec]] = {
    name: _spec_class(kind) for name, kind in AGENT_KINDS.items()
}
# each also under its own name here (PedestrianTraffic, ...), where pickle looks for it when a
# scenario goes to a worker process
globals().update({spec.__name__: spec for spec in TRAFFIC_SPECS.values()})


class _TrafficClassesBase(Spec):
    """One entry per agent class; an omitted class does not appear."""

    def all(self) -> tuple[TrafficClassSpec, ...]:
        """Every class's spec, in registry order (the order of their random streams)."""
        return tuple(getattr(self, name) for name in AGENT_KINDS)

    def of(self, kind: str) -> TrafficClassSpec:
        return getattr(self, kind)


TrafficClasses = create_model(
    "TrafficClasses", __base__=_TrafficClassesBase, __module__=__name__,
    __doc__=_TrafficClassesBase.__doc__,
    **{name: (spec, spec()) for name, spec in TRAFFIC_SPECS.items()},
)  # fmt: skip


class ScriptedAgent(Spec):
    """One agent that enters at a set time: a test object for a planner (a 60 km/h car at 22:05)."""

    cls: Literal[TARGET_KINDS]  # any target kind
    t_s: float = Field(ge=0, description="simulated time it enters the street, s")
    speed_kmh: float = Field(gt=0, le=MAX_SPEED_KMH, description="its desired speed")
    direction: Literal[1, -1] = Field(default=1, description="+1: toward +x, -1: toward -x")
    path: int = Field(
        default=0, ge=0, description="index of its lane (road users) or sidewalk (walkers)"
    )
    light_on: bool | None = Field(
        default=None, description="its light; default: at night if most of its kind ride lit"
    )


class TrafficSpec(Spec):
    classes: TrafficClasses = TrafficClasses()
    scripted: tuple[ScriptedAgent, ...] = Field(
        default=(), description="agents that enter at set times, on top of the random arrivals"
    )

    def reported_kinds(self) -> tuple[str, ...]:
        """Target kinds a run's per-class figures list: every kind that is itself one of the
        detector's classes (fixed columns, to compare runs and the paper), and any other
        target kind this scenario has traffic of."""
        scripted = {a.cls for a in self.scripted}
        return tuple(
            name for name in TARGET_KINDS
            if name in DETECTOR_CLASSES
            or self.classes.of(name).rate_per_hour > 0
            or name in scripted
        )  # fmt: skip
