"""The city file (CITY.yaml): which streets, where the city lies, and what the hardware costs.

::

    streets: [streets/a.yaml, /abs/b.yaml]   # scenario files, relative to the city file or absolute
    osm:                                     # and/or streets selected from an OpenStreetMap extract
      file: extract.osm.pbf                  #   relative to the city file or absolute
      highway: [residential]                 #   the ways' highway classes
      min_lamps: 4                           #   at least this many street lamps along the way
      lamps_within_m: 15.0                   #   a lamp belongs to a way within this distance, m
    site: {latitude_deg: 51.2, longitude_deg: 6.8, timezone: Europe/Berlin, year: 2025}
    costs: {...}                             # citysim.config.costs.CostsSpec; every street's own
                                             # costs section is replaced by this one

The site and the costs are shared by every street: each street's own ``year`` site (latitude,
longitude, time zone, year) and ``costs`` are overridden by the city's.
"""

from __future__ import annotations

from pathlib import Path

from pydantic import Field, ValidationError, field_validator, model_validator

from citysim.config.base import ScenarioError, Spec, describe_validation_error
from citysim.config.costs import CostsSpec
from citysim.config.year import YearSpec
from detector.yamlfile import read_yaml_mapping


class CityError(ScenarioError):
    """A city file that cannot be used; the message names the file and the field."""


class OsmSelection(Spec):
    """Streets of an OpenStreetMap extract: every way of the given highway classes with enough lamps."""

    file: str = Field(min_length=1, description="OSM extract (.osm or .osm.pbf), relative to the city file")
    highway: tuple[str, ...] = Field(default=("residential",), min_length=1,
                                     description="highway classes of the ways to take, e.g. [residential]")
    min_lamps: int = Field(default=4, ge=1, le=10_000, description="fewest street lamps a way must have")
    lamps_within_m: float = Field(default=15.0, gt=0, le=200,
                                  description="a street lamp belongs to a way within this distance, m")


class SiteSpec(Spec):
    """Where the city lies and which year is summed (replaces every street's own ``year`` site)."""

    latitude_deg: float = Field(ge=-90, le=90, description="site latitude, north positive")
    longitude_deg: float = Field(ge=-180, le=180, description="site longitude, east positive")
    timezone: str = Field(min_length=1, description="IANA time zone, e.g. Europe/Berlin")
    year: int | None = Field(default=None, ge=1900, le=2200, description="calendar year (default: each street's)")

    @field_validator("timezone")
    @classmethod
    def _zone(cls, v: str) -> str:
        try:
            YearSpec(latitude_deg=0.0, longitude_deg=0.0, timezone=v)
        except ValidationError as exc:
            raise ValueError(exc.errors()[0]["msg"].removeprefix("Value error, ")) from None
        return v


class CitySpec(Spec):
    """A city file's contents (see the module docstring)."""

    name: str | None = Field(default=None, pattern=r"^[A-Za-z0-9_. -]+$", max_length=80,
                             description="the city's name (default: the city file's name)")
    streets: tuple[str, ...] = Field(default=(), description="scenario files, relative to the city file")
    osm: OsmSelection | None = None
    site: SiteSpec
    costs: CostsSpec | None = Field(default=None, description="costs for every street (default: each street's own)")

    @model_validator(mode="after")
    def _some_streets(self) -> CitySpec:
        if not self.streets and self.osm is None:
            raise ValueError("give `streets:` (a list of scenario files) or `osm:` (an extract and a selection)")
        return self


def load_city(path: str | Path) -> CitySpec:
    """Read and validate a city file; street files must exist. Raises CityError naming file and field."""
    path = Path(path)
    data = read_yaml_mapping(path, "city", CityError, holds="sections")
    try:
        city = CitySpec.model_validate(data)
    except ValidationError as exc:
        raise CityError(f"{path}: {describe_validation_error(exc, CitySpec)}") from None
    for i, street in enumerate(city.streets):
        if not street_path(path, street).is_file():
            raise CityError(f"{path}: streets.{i}: no scenario file {street_path(path, street)}")
    if city.osm is not None and not street_path(path, city.osm.file).is_file():
        raise CityError(f"{path}: osm.file: no file {street_path(path, city.osm.file)}")
    return city


def street_path(city_file: Path, entry: str) -> Path:
    """A path of the city file, absolute or relative to the city file's folder."""
    p = Path(entry).expanduser()
    return p if p.is_absolute() else Path(city_file).parent / p


def city_name(city: CitySpec, city_file: Path) -> str:
    return city.name or Path(city_file).stem
