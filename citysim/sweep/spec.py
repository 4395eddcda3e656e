"""Sweep files: the YAML schema of a parameter sweep and its expansion into points.

A sweep names a base scenario (a path relative to the sweep file), axes over
scenario fields by dotted path (``lamps.camera.tilt_deg: [0, 20, 40]``) or over
a derived quantity from ``DERIVED_AXES`` (``traffic_density: [0.5, 1, 2]``
multiplies every target class's arrival rate), fixed overrides (``set``), the
seeds, a ``duration_s`` override and the controllers to compare. The points
are the Cartesian product of the axes (in file order) times the seeds; each
has a ``point_id``, a stable hash of its axis values and seed, so a results
table can tell which points are finished whichever order they ran in.

``load_sweep(path)`` validates the file (unknown keys and misspelt scenario
paths are errors) and raises ``SweepError`` whose one message starts with the
file and the dotted field path.
"""

from __future__ import annotations

import difflib
import hashlib
import itertools
import json
import types
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from citysim.config.kinds import TARGET_KINDS
from citysim.config.scenario import ControllerSpec, Scenario, ScenarioError, load_scenario, override
from detector.yamlfile import read_yaml_mapping

__all__ = [
    "DERIVED_AXES",
    "ResolvedSweep",
    "SweepError",
    "SweepPoint",
    "SweepSpec",
    "load_sweep",
    "point_id",
]


class SweepError(ValueError):
    """A sweep file that cannot be used; the message starts with the file and the field path."""


def _scale_traffic(scenario: Scenario, factor: float) -> dict[str, float]:
    """Overrides that multiply the arrival rate of every target class (animals are not traffic)."""
    if not isinstance(factor, (int, float)) or isinstance(factor, bool) or factor < 0:
        raise ScenarioError(f"traffic_density: a multiplier >= 0, got {factor!r}")
    classes = scenario.traffic.classes
    return {
        f"traffic.classes.{kind}.rate_per_hour": getattr(classes, kind).rate_per_hour * factor
        for kind in TARGET_KINDS
    }


def _lead_time(scenario: Scenario, seconds: float) -> dict[str, float]:
    """Overrides that give every controller which lights ahead (``lead_s``) this lead time."""
    if not isinstance(seconds, (int, float)) or isinstance(seconds, bool) or seconds < 0:
        raise ScenarioError(f"lead_s: seconds >= 0, got {seconds!r}")
    return {f"controllers.{i}.lead_s": float(seconds) for i, c in enumerate(scenario.controllers)
            if c.name == "detector_located"}  # fmt: skip


def _zone_probability(scenario: Scenario, p: float) -> dict[str, float]:
    """Overrides that give every ``detector_fused`` this zone-probability threshold (0 < p < 1)."""
    if not isinstance(p, (int, float)) or isinstance(p, bool) or not 0 < p < 1:
        raise ScenarioError(f"zone_probability: a probability between 0 and 1 (exclusive), got {p!r}")
    return {f"controllers.{i}.zone_probability": float(p) for i, c in enumerate(scenario.controllers)
            if c.name == "detector_fused"}  # fmt: skip


#: Axes that are not one scenario field: name -> (scenario, value) -> dotted-path overrides.
DERIVED_AXES: dict[str, Callable[[Scenario, Any], dict[str, Any]]] = {
    "traffic_density": _scale_traffic,
    "lead_s": _lead_time,
    "zone_probability": _zone_probability,
}

AxisValue = int | float | str | bool


class SweepSpec(BaseModel):
    """The sweep file as written (paths unresolved)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    name: str = Field(pattern=r"^[A-Za-z0-9_.-]+$", max_length=80)
    description: str = ""
    base: str = Field(min_length=1, description="scenario file, relative to the sweep file")
    duration_s: float | None = Field(
        default=None, gt=0, le=7 * 86400, description="overrides the scenario's"
    )
    seeds: tuple[int, ...] | None = Field(
        default=None, min_length=1, description="default: the scenario's seed"
    )
    controllers: tuple[ControllerSpec, ...] | None = Field(
        default=None, min_length=1, description="default: the scenario's"
    )
    set: dict[str, Any] = Field(
        default_factory=dict, description="dotted path -> value, every point"
    )
    axes: dict[str, tuple[AxisValue, ...]] = Field(
        default_factory=dict, description="dotted path or derived axis -> values"
    )
    save_objects: bool = Field(
        default=True, description="keep each point's objects.csv (lag CDF plots)"
    )

    @field_validator("seeds")
    @classmethod
    def _seeds(cls, v: tuple[int, ...] | None) -> tuple[int, ...] | None:
        if v is None:
            return v
        for i, s in enumerate(v):
            if s < 0:
                raise ValueError(f"seeds must be >= 0, got {s} (entry {i})")
        if len(set(v)) != len(v):
            raise ValueError(f"seeds must be distinct, got {list(v)}")
        return v

    @field_validator("axes")
    @classmethod
    def _axes(cls, v: dict[str, tuple[AxisValue, ...]]) -> dict[str, tuple[AxisValue, ...]]:
        for name, values in v.items():
            if not values:
                raise ValueError(f"axis {name!r} needs at least one value")
            if len({json.dumps(x) for x in values}) != len(values):
                raise ValueError(f"axis {name!r} repeats a value: {list(values)}")
        return v


@dataclass(frozen=True)
class SweepPoint:
    """One task: axis values (in axis order) and a seed."""

    point_id: str
    values: tuple[tuple[str, AxisValue], ...]
    seed: int

    @property
    def axes(self) -> dict[str, AxisValue]:
        return dict(self.values)


def point_id(values: Mapping[str, AxisValue], seed: int) -> str:
    """Stable 12-hex-digit id of a point: the same axis values and seed give the same id anywhere."""
    text = json.dumps({"axes": dict(values), "seed": int(seed)}, sort_keys=True)
    return hashlib.sha1(text.encode()).hexdigest()[:12]


@dataclass(frozen=True)
class ResolvedSweep:
    """A validated sweep: the base scenario with ``set``, ``duration_s`` and controllers applied."""

    spec: SweepSpec
    sweep_file: Path
    base_file: Path
    base: Scenario
    seeds: tuple[int, ...]

    @property
    def controller_labels(self) -> tuple[str, ...]:
        return tuple(c.display_name for c in self.base.controllers)

    @property
    def axis_names(self) -> tuple[str, ...]:
        return tuple(self.spec.axes)

    def points(self) -> list[SweepPoint]:
        """Cartesian product of the axes (file order) x seeds."""
        names = self.axis_names
        grid = itertools.product(*(self.spec.axes[n] for n in names)) if names else [()]
        out = []
        for combo in grid:
            values = tuple(zip(names, combo, strict=True))
            for seed in self.seeds:
                out.append(SweepPoint(point_id(dict(values), seed), values, seed))
        return out

    def scenario_for(self, point: SweepPoint) -> Scenario:
        """The point's validated scenario; ScenarioError names the point and the field."""
        plain = {k: v for k, v in point.values if k not in DERIVED_AXES}
        scenario = override(self.base, {**plain, "seed": point.seed})
        for name, value in point.values:
            if name in DERIVED_AXES:
                scenario = override(scenario, DERIVED_AXES[name](scenario, value))
        return scenario

    def fingerprint(self) -> str:
        """Hash of everything a row depends on besides the point itself (base, duration, controllers)."""
        text = json.dumps(self.base.model_dump(mode="json", exclude={"seed"}), sort_keys=True)
        return hashlib.sha1(text.encode()).hexdigest()[:16]

    def to_json(self) -> dict[str, Any]:
        """The resolved sweep as written to DIR/sweep.json."""
        return {
            "name": self.spec.name,
            "description": self.spec.description,
            "sweep_file": str(self.sweep_file),
            "base_file": str(self.base_file),
            "scenario": self.base.name,
            "duration_s": self.base.duration_s,
            "start_hour": self.base.start_hour,
            "lamps": len(self.base.lamps.positions_x_m),
            "seeds": list(self.seeds),
            "controllers": list(self.controller_labels),
            "set": self.spec.set,
            "axes": {k: list(v) for k, v in self.spec.axes.items()},
            "points": len(self.points()),
            "save_objects": self.spec.save_objects,
            "fingerprint": self.fingerprint(),
        }


def _format_errors(exc: ValidationError) -> str:
    parts = []
    for err in exc.errors():
        where = ".".join(str(p) for p in err["loc"]) or "(top level)"
        msg = err["msg"].removeprefix("Value error, ")
        if err["type"] == "extra_forbidden":
            near = difflib.get_close_matches(str(err["loc"][-1]), list(SweepSpec.model_fields), n=3)
            hint = f"did you mean {' or '.join(near)}?" if near else f"valid: {', '.join(SweepSpec.model_fields)}"
            msg = f"unknown field; {hint}"
        parts.append(f"{where}: {msg}")
    return "; ".join(parts)


def _unwrap(annotation: Any) -> Any:
    """Strip Optional/Union-with-None so the path walk sees the model or container inside."""
    origin = typing.get_origin(annotation)
    if origin in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(annotation) if a is not type(None)]
        return _unwrap(args[0]) if len(args) == 1 else annotation
    return annotation


def scenario_path_problem(dotted: str) -> str | None:
    """Why ``dotted`` is not a scenario field path (None if it is one), e.g. a misspelt key."""
    node: Any = Scenario
    walked: list[str] = []
    for key in dotted.split("."):
        node = _unwrap(node)
        origin = typing.get_origin(node)
        if isinstance(node, type) and issubclass(node, BaseModel):
            if key not in node.model_fields:
                where = ".".join(walked) or "the scenario"
                near = difflib.get_close_matches(key, list(node.model_fields), n=3)
                hint = f"did you mean {' or '.join(near)}?" if near else f"valid: {', '.join(node.model_fields)}"
                return f"{key!r} is not a field of {where}; {hint}"
            node = node.model_fields[key].annotation
        elif origin in (tuple, list):
            if not key.isdigit():
                return f"{'.'.join(walked)} is a list: address an item by index, got {key!r}"
            node = typing.get_args(node)[0]
        elif origin is dict:
            node = typing.get_args(node)[1]
        else:
            return f"{'.'.join(walked)} is a value, it has no field {key!r}"
        walked.append(key)
    return None


def load_sweep(path: str | Path) -> ResolvedSweep:
    """Read and validate a sweep YAML file; raise SweepError naming the file and field."""
    path = Path(path)
    data = read_yaml_mapping(path, "sweep", SweepError)
    try:
        spec = SweepSpec.model_validate(data)
    except ValidationError as exc:
        raise SweepError(f"{path}: {_format_errors(exc)}") from None
    return resolve(spec, path)


def resolve(spec: SweepSpec, sweep_file: Path) -> ResolvedSweep:
    """Check the paths and controllers of ``spec`` and build the base scenario."""
    from citysim.control.registry import CONTROLLERS

    src = str(sweep_file)
    own_keys = {"seed": "seeds", "duration_s": "duration_s", "controllers": "controllers"}
    for section in ("set", "axes"):
        for dotted in getattr(spec, section):
            if section == "axes" and dotted in DERIVED_AXES:
                continue
            if dotted in own_keys:
                raise SweepError(
                    f"{src}: {section}.{dotted}: use the sweep's own `{own_keys[dotted]}` key"
                )
            problem = scenario_path_problem(dotted)
            if problem:
                derived = (
                    f" (or a derived axis: {', '.join(DERIVED_AXES)})" if section == "axes" else ""
                )
                raise SweepError(f"{src}: {section}.{dotted}: {problem}{derived}")
    for i, c in enumerate(spec.controllers or ()):
        if c.name not in CONTROLLERS:
            raise SweepError(
                f"{src}: controllers.{i}.name: unknown {c.name!r}; valid: {', '.join(CONTROLLERS)}"
            )
    base_file = (sweep_file.parent / spec.base).resolve()
    try:
        base = load_scenario(base_file)
        updates: dict[str, Any] = dict(spec.set)
        if spec.duration_s is not None:
            updates["duration_s"] = spec.duration_s
        if spec.controllers is not None:
            updates["controllers"] = [
                c.model_dump(mode="python", exclude_unset=True) for c in spec.controllers
            ]
        if updates:
            base = override(base, updates)
    except ScenarioError as exc:
        raise SweepError(f"{src}: base/set: {exc}") from None
    if not any(c.name == "always_on" for c in base.controllers):
        # savings are always measured against always-on in the same run (sim adds it too)
        base = override(
            base,
            {"controllers": [{"name": "always_on"}]
             + [c.model_dump(mode="python", exclude_unset=True) for c in base.controllers]},
        )  # fmt: skip
    for i, c in enumerate(base.controllers):
        if c.name not in CONTROLLERS:
            raise SweepError(
                f"{src}: base scenario controllers.{i}.name: unknown {c.name!r}; valid: {', '.join(CONTROLLERS)}"
            )
    seeds = spec.seeds if spec.seeds is not None else (base.seed,)
    return ResolvedSweep(spec, sweep_file.resolve(), base_file, base, seeds)
