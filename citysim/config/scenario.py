"""Scenario files: the YAML schema, loading and validation with field-path errors.

``load_scenario(path)`` turns a YAML file into a frozen, validated ``Scenario``
or raises ``ScenarioError`` whose one message starts with the file and the
dotted path of each bad field (``lamps.camera.tilt_deg: ...``) and says what is
valid. Every section is a frozen pydantic model that forbids unknown keys; the
street, lamp and traffic sections live in ``citysim.config.street`` and
``citysim.config.traffic``. Past the loader, code passes these typed objects, never
dicts. ``override(scenario, {"lamps.camera.tilt_deg": 20})`` makes a validated
variant (parameter sweeps).

Time: ``start_hour`` is the clock hour at t = 0 (22.0 = 10 pm); simulated time
runs from 0 to ``duration_s`` seconds.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal

from pydantic import Field, ValidationError, create_model, field_validator, model_validator

from citysim.config.base import FieldPathError, ScenarioError, Spec, describe_validation_error
from citysim.config.costs import CostsSpec
from citysim.config.kinds import AGENT_KINDS
from citysim.config.street import LampsSpec, StreetSpec
from citysim.config.traffic import TrafficSpec
from citysim.config.year import YearSpec
from detector.yamlfile import read_yaml_mapping

__all__ = [
    "ControllerSpec",
    "EnvironmentSpec",
    "NetworkSpec",
    "Scenario",
    "ScenarioError",
    "SimulationSpec",
    "load_scenario",
    "override",
    "scenario_from_mapping",
]


class EnvironmentSpec(Spec):
    """What the night is like for the cameras: light, weather, wind, insects, and the camera
    sensor's noise, exposure and lens. The renderer reads this very object."""

    time_of_day: Literal["night", "day"] = "night"
    weather: Literal["clear", "rain"] = "clear"
    wind_mps: float = Field(default=2.0, ge=0, le=40, description="sways branches")
    insects_per_min: float = Field(
        default=0.0, ge=0, le=10000, description="insects crossing the IR emitter"
    )
    animals_per_hour: float | None = Field(
        default=None, ge=0, le=10000, description="same as traffic.classes.animal.rate_per_hour"
    )
    sensor_noise_std_dn: float = Field(default=3.0, ge=0, le=64)
    exposure_ms: float = Field(default=30.0, gt=0, le=1000)
    lens_distortion: bool = True
    rain_drops_per_frame: int = Field(
        default=120, ge=0, le=100_000, description="rain streaks per frame when weather is rain"
    )

    @property
    def ambient_light(self) -> float:
        """Daylight on the scene, 0 (night: only lamps and the IR emitter) to 1 (day)."""
        return 1.0 if self.time_of_day == "day" else 0.0


#: How many lamps ahead of a detected object a controller lights, per class the detector
#: reports (the kinds that are a detector class; defaults: ``AgentKind.lamps_ahead``).
NeighboursAhead = create_model(
    "NeighboursAhead", __base__=Spec, __module__=__name__,
    __doc__="How many lamps ahead of a detected object a controller lights, per class.",
    **{k.name: (int, Field(default=k.lamps_ahead, ge=0, le=20)) for k in AGENT_KINDS.values()
       if k.is_target and k.name == k.detector_class},
)  # fmt: skip


class NetworkSpec(Spec):
    """Wireless links between lamps."""

    latency_ms: float = Field(default=20.0, ge=0, le=10000)
    jitter_ms: float = Field(default=5.0, ge=0, le=10000)
    loss_probability: float = Field(
        default=0.01, ge=0, le=1, description="share of message copies lost (1: a dead radio)"
    )
    repeat_s: float = Field(
        default=3.0, gt=0, le=600, description="a lit lamp repeats its message this often"
    )
    neighbours_ahead: NeighboursAhead = NeighboursAhead()


class SimulationSpec(Spec):
    """How hard the simulator looks: trade exactness for speed, never the traffic."""

    idle_frame_stride: int = Field(
        default=15,
        ge=1,
        le=30,
        description="an idle lamp camera (nobody in view, steady light, no motion in its last judged "
        "frame) is judged every n-th frame; 1 judges every frame of every camera (exact, slow)",
    )


class ScheduleStep(Spec):
    start_hour: float = Field(ge=0, lt=24, description="clock hour this level starts")
    level: float = Field(ge=0, le=1)


class ControllerSpec(Spec):
    """One controller to compare: a registered name plus optional parameters.

    A bare string in the YAML list is shorthand for ``{name: <string>}``. The
    names are checked against the controller registry when a run starts.
    """

    name: str = Field(
        pattern=r"^[a-z][a-z0-9_]*$", description="registry key, e.g. always_on, detector"
    )
    label: str | None = Field(
        default=None, min_length=1, max_length=60, description="name in results; default: name"
    )
    threshold_fraction: float | None = Field(
        default=None, gt=0, le=1, description="naive baseline: foreground share"
    )
    target_threshold: float | None = Field(
        default=None, ge=0, le=1, description="detector: P(target) to light"
    )
    k: int | None = Field(default=None, ge=1, le=100, description="k-of-n confirmation (eq. 12)")
    tracking: bool | None = Field(
        default=None, description="camera controllers: decide per track of the detector (true) or per frame "
        "(false); default: the controller's own (detector_tracked and detector_located track)",
    )
    n: int | None = Field(default=None, ge=1, le=100)
    hold_s: float | None = Field(
        default=None, ge=0, le=3600, description="overrides lamps.luminaire.hold_s"
    )
    lead_s: float | None = Field(
        default=None, ge=0, le=60,
        description="detector_located: light zones a target enters within this many seconds "
        "(plus a class margin); default: ramp + radio latency + one frame",
    )
    light_blind_ends: bool | None = Field(
        default=None,
        description="detector_located: keep an end lamp at full when no camera watches the approach "
        "to its zone (whoever comes from there arrives unseen); default true",
    )
    zone_probability: float | None = Field(
        default=None, gt=0, lt=1,
        description="detector_fused: light a zone while P(some street track is in it or enters it within "
        "the lead) reaches this; default 0.3",
    )
    schedule: tuple[ScheduleStep, ...] = ()

    @model_validator(mode="before")
    @classmethod
    def _shorthand(cls, data: Any) -> Any:
        return {"name": data} if isinstance(data, str) else data

    @model_validator(mode="after")
    def _k_of_n(self) -> ControllerSpec:
        if (self.k is None) != (self.n is None):
            raise FieldPathError(
                ("n" if self.n is None else "k",),
                "give both k and n (k-of-n confirmation), or neither",
            )
        if self.k is not None and self.k > self.n:
            raise FieldPathError(("k",), f"must be <= n ({self.n}), got {self.k}")
        return self

    @property
    def display_name(self) -> str:
        return self.label or self.name


class Scenario(Spec):
    """A complete, validated scenario (see scenarios/suburban_night.yaml for every field)."""

    name: str = Field(pattern=r"^[A-Za-z0-9_.-]+$", max_length=80)
    description: str = ""
    seed: int = Field(ge=0)
    duration_s: float = Field(gt=0, le=7 * 86400)
    start_hour: float = Field(default=22.0, ge=0, lt=24, description="clock hour at t = 0")
    physics_hz: float = Field(default=30.0, gt=0, le=240)
    street: StreetSpec
    lamps: LampsSpec
    traffic: TrafficSpec = TrafficSpec()
    environment: EnvironmentSpec = EnvironmentSpec()
    network: NetworkSpec = NetworkSpec()
    simulation: SimulationSpec = SimulationSpec()
    controllers: tuple[ControllerSpec, ...] = (ControllerSpec(name="always_on"),)
    year: YearSpec | None = Field(default=None, description="site, tariff and traffic by day for `citysim year`")
    costs: CostsSpec = Field(default=CostsSpec(), description="hardware, upkeep and energy prices for payback and NPV")

    @model_validator(mode="before")
    @classmethod
    def _animals_once(cls, data: Any) -> Any:
        """environment.animals_per_hour and traffic.classes.animal.rate_per_hour are one number."""
        if not isinstance(data, dict):
            return data
        env, traffic = data.get("environment") or {}, data.get("traffic") or {}
        if (
            not isinstance(env, dict)
            or not isinstance(traffic, dict)
            or not isinstance(traffic.get("classes", {}), dict)
        ):
            return data
        animal = (traffic.get("classes") or {}).get("animal") or {}
        if not isinstance(animal, dict):
            return data
        env_rate, traffic_rate = env.get("animals_per_hour"), animal.get("rate_per_hour")
        if env_rate is not None and traffic_rate is not None and env_rate != traffic_rate:
            raise FieldPathError(
                ("environment", "animals_per_hour"),
                f"{env_rate} conflicts with traffic.classes.animal.rate_per_hour={traffic_rate}; give one of them",
            )
        rate = traffic_rate if traffic_rate is not None else env_rate
        if rate is None:
            rate = 0.0
        data = copy.deepcopy(data)
        data.setdefault("environment", {})
        data["environment"] = {**(data["environment"] or {}), "animals_per_hour": rate}
        data.setdefault("traffic", {})
        data["traffic"] = dict(data["traffic"] or {})
        data["traffic"]["classes"] = dict(data["traffic"].get("classes") or {})
        data["traffic"]["classes"]["animal"] = {**animal, "rate_per_hour": rate}
        return data

    @field_validator("controllers")
    @classmethod
    def _unique_labels(cls, v: tuple[ControllerSpec, ...]) -> tuple[ControllerSpec, ...]:
        if not v:
            raise ValueError("name at least one controller, e.g. [always_on, detector]")
        seen: dict[str, int] = {}
        for i, c in enumerate(v):
            if c.display_name in seen:
                raise FieldPathError(
                    (i, "label"),
                    f"{c.display_name!r} is used twice (entries {seen[c.display_name]} and {i}); give each a label",
                )
            seen[c.display_name] = i
        return v

    @model_validator(mode="after")
    def _fits_street(self) -> Scenario:
        street, lamps = self.street, self.lamps
        xs = lamps.positions_x_m
        for i, x in enumerate(xs):
            if not 0 <= x <= street.length_m:
                where = ("lamps", "x_m", i) if lamps.x_m is not None else ("lamps", "count")
                where = ("lamps", "poles", i, "s_m") if lamps.poles is not None else where
                raise FieldPathError(
                    where,
                    f"lamp {i} at x={x:g} m lies outside the street (0..{street.length_m:g} m)",
                )
        # surveyed poles stand where they were surveyed (on a sidewalk, a wall): no clearance check
        problem = None if lamps.poles is not None else street.pole_clearance_problem(lamps.y_m)
        if problem:
            raise FieldPathError(("lamps", "y_m"), problem)
        classes = self.traffic.classes
        walkers = [s for s in classes.all() if AGENT_KINDS[s.kind].route == "sidewalk"]
        for spec in walkers:
            if spec.rate_per_hour > 0 and not street.sidewalks:
                raise FieldPathError(
                    ("traffic", "classes", spec.kind, "rate_per_hour"),
                    "walkers need street.sidewalks; set 0 or add one",
                )
            if spec.rate_per_hour > 0 and spec.crossing_fraction > 0 and not street.has_both_sides:
                raise FieldPathError(
                    ("traffic", "classes", spec.kind, "crossing_fraction"),
                    "crossing needs a sidewalk on each side of the road; set 0 or add one",
                )
        frame_s = 1.0 / lamps.camera_model.fps
        if lamps.luminaire.hold_s < frame_s:
            raise FieldPathError(
                ("lamps", "luminaire", "hold_s"),
                f"must be at least one camera frame ({frame_s:.3f} s at {lamps.camera_model.fps:g} fps), "
                f"or the lamp drops between two frames that both see someone; got {lamps.luminaire.hold_s}",
            )
        for i, c in enumerate(self.controllers):
            if c.hold_s is not None and c.hold_s < frame_s:
                raise FieldPathError(
                    ("controllers", i, "hold_s"),
                    f"must be at least one camera frame ({frame_s:.3f} s); got {c.hold_s}",
                )
        for i, agent in enumerate(self.traffic.scripted):
            road_user = AGENT_KINDS[agent.cls].road_user
            paths = street.lanes if road_user else street.sidewalks
            kind = "street.lanes" if road_user else "street.sidewalks"
            if agent.path >= len(paths):
                raise FieldPathError(
                    ("traffic", "scripted", i, "path"),
                    f"{agent.cls} path {agent.path} does not exist; valid: 0..{len(paths) - 1} ({kind})",
                )
        for spec in (s for s in classes.all() if AGENT_KINDS[s.kind].road_user):
            if spec.rate_per_hour > 0 and not street.lanes:
                raise FieldPathError(
                    ("traffic", "classes", spec.kind, "rate_per_hour"),
                    f"{spec.kind}s need street.lanes; set 0 or add one",
                )
        return self

    @property
    def night(self) -> bool:
        return self.environment.time_of_day == "night"


def scenario_from_mapping(
    data: Mapping[str, Any], source: str = "scenario", base_dir: str | Path | None = None
) -> Scenario:
    """Validate a mapping; camera files resolve against ``base_dir``; errors name ``source``."""
    try:
        return Scenario.model_validate(dict(data), context={"base_dir": base_dir})
    except ValidationError as exc:
        raise ScenarioError(f"{source}: {describe_validation_error(exc)}") from None
    except FieldPathError as exc:  # raised by a before-validator outside pydantic's wrapping
        raise ScenarioError(f"{source}: {'.'.join(map(str, exc.path))}: {exc}") from None


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario YAML file; raise ScenarioError naming the file and field."""
    path = Path(path)
    data = read_yaml_mapping(path, "scenario", ScenarioError, holds="sections")
    return scenario_from_mapping(data, source=str(path), base_dir=path.parent)


def override(scenario: Scenario, updates: Mapping[str, Any]) -> Scenario:
    """A validated copy with dotted-path fields replaced, e.g. ``{"lamps.camera.tilt_deg": 20}``.

    List items are addressed by index (``street.lanes.0.width_m``). Errors name
    the scenario and the dotted path.
    """
    data = _lists(scenario.model_dump(mode="python", exclude_unset=True))
    # the animal rate is stored twice (environment and traffic); keep the one being changed
    if any(k.startswith("environment.animals_per_hour") for k in updates):
        data.get("traffic", {}).get("classes", {}).get("animal", {}).pop("rate_per_hour", None)
    else:
        data.get("environment", {}).pop("animals_per_hour", None)
    for dotted, value in updates.items():
        keys = dotted.split(".")
        node: Any = data
        for key in keys[:-1]:
            if isinstance(node, (list, tuple)):
                node = node[int(key)]
            else:
                node = node.setdefault(key, {})
        if isinstance(node, (list, tuple)):
            node[int(keys[-1])] = value
        else:
            node[keys[-1]] = value
    return scenario_from_mapping(data, source=f"{scenario.name} (override)")


def _lists(obj: Any) -> Any:
    """Tuples from model_dump -> lists, so overrides can assign into them."""
    if isinstance(obj, dict):
        return {k: _lists(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_lists(v) for v in obj]
    return obj
