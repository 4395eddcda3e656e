"""A city's streets made ready to run: each scenario loaded, the city's site and costs put in.

``prepare_streets`` loads every scenario file, replaces its ``costs`` section by the city's (when
the city gives one) and its year's site (latitude, longitude, time zone, and year when the city
names one) by the city's, applies ``--sample-s``, checks the controllers, and names each street
(its scenario's name; a name taken twice gets ``-2``, ``-3``, ... in the order of the city file).
Everything a task needs travels in its ``StreetJob``.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

from citysim.city.spec import CitySpec, SiteSpec
from citysim.config.base import ScenarioError
from citysim.config.scenario import Scenario, load_scenario, override
from citysim.config.year import YearSpec
from citysim.year.plan import year_spec


@dataclass(frozen=True)
class StreetJob:
    """One street's year: its name, scenario file, scenario (city costs in), year settings (city site in)."""

    name: str
    source: str
    scenario: Scenario
    year: YearSpec
    controllers: tuple[str, ...] | None
    fidelity: str

    def fingerprint(self) -> str:
        """A hash of everything the street's year.json depends on (a resumed run must match it)."""
        parts = [self.scenario.model_dump(mode="json"), self.year.model_dump(mode="json"),
                 self.controllers, self.fidelity]  # fmt: skip
        return hashlib.sha256(json.dumps(parts, sort_keys=True, default=str).encode()).hexdigest()[:16]


def site_overrides(site: SiteSpec, sample_s: float | None) -> dict:
    """The year fields the city sets for every street (None: the street's own)."""
    return {"latitude_deg": site.latitude_deg, "longitude_deg": site.longitude_deg, "timezone": site.timezone,
            "year": site.year, "sample_s": sample_s}  # fmt: skip


def prepare_street(path: Path, city: CitySpec, *, sample_s: float | None = None,
                   controllers: tuple[str, ...] | None = None, fidelity: str = "fast") -> StreetJob:  # fmt: skip
    """One street's job (its name is the scenario's; ``prepare_streets`` makes names unique)."""
    from citysim.sim.compare import resolve_controllers

    scenario = load_scenario(path)
    if city.costs is not None:
        scenario = override(scenario, {"costs": city.costs.model_dump(mode="json", exclude_unset=True)})
    year = year_spec(scenario, str(path), **site_overrides(city.site, sample_s))
    resolve_controllers(scenario, list(controllers) if controllers else None)  # unknown names fail now
    return StreetJob(scenario.name, str(path), scenario, year, controllers, fidelity)


def prepare_streets(paths: list[Path], city: CitySpec, **options) -> list[StreetJob]:
    """Every street's job, in the city file's order, with unique names; errors name the file and field."""
    jobs: list[StreetJob] = []
    taken: dict[str, int] = {}
    for path in paths:
        try:
            job = prepare_street(path, city, **options)
        except ValueError as exc:
            if isinstance(exc, ScenarioError):
                raise
            raise ScenarioError(f"{path}: {exc}") from None
        taken[job.name] = taken.get(job.name, 0) + 1
        if taken[job.name] > 1:
            job = StreetJob(f"{job.name}-{taken[job.name]}", job.source, job.scenario, job.year, job.controllers,
                            job.fidelity)  # fmt: skip
        jobs.append(job)
    return jobs
