"""`citysim city`'s work in one call: the city file's streets, their years on Dask, city.json and city.csv.

``run_city`` prepares every street (``citysim.city.streets``: the city's site and costs put in),
runs the unfinished ones (``citysim.city.runner``), and writes DIR/city.json and DIR/city.csv
from all the streets' year.json (``citysim.city.results``). Drawing the map and the report is the
command's (``citysim.report.city_report``), which reads city.json only.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from citysim.city.results import city_result, write_city
from citysim.city.runner import run_streets, street_dir
from citysim.city.spec import CitySpec, city_name, street_path
from citysim.city.streets import StreetJob, prepare_streets

#: What a city folder holds; an earlier folder of the same city resumes.
CITY_OUTPUTS = ("city.json", "city.csv", "streets/", "osm_streets/", "plots/", "report.html")


@dataclass(frozen=True)
class CityOptions:
    """How to run a city: controllers (None: each street's own list), sample_s (None: each street's),
    fidelity, the share of zone entries the ranking requires lit on entry, and where the work runs."""

    controllers: tuple[str, ...] | None = None
    sample_s: float | None = None
    fidelity: str = "fast"
    min_lit_on_entry: float = 0.99
    scheduler: str | None = None
    workers: int | None = None
    progress: bool = True
    cache_dir: Path | None = None


def city_jobs(city: CitySpec, city_file: Path, out_dir: Path, options: CityOptions) -> list[StreetJob]:
    """Every street of the city file (listed files, then the OSM selection), ready to run."""
    paths = [street_path(city_file, entry) for entry in city.streets]
    if city.osm is not None:
        from citysim.city.from_osm import osm_street_files

        paths += osm_street_files(city.osm, city_file, out_dir)
    return prepare_streets(paths, city, sample_s=options.sample_s, controllers=options.controllers,
                           fidelity=options.fidelity)  # fmt: skip


def shared_models(jobs: list[StreetJob]) -> dict[str, list[str]]:
    """Camera key -> the streets that share its sensor model (streets needing none are not listed)."""
    from citysim.city.models import camera_key, needs_model

    groups: dict[str, list[str]] = {}
    for job in jobs:
        if needs_model(job):
            groups.setdefault(camera_key(job), []).append(job.name)
    return groups


def run_city(city: CitySpec, city_file: Path, out_dir: Path, options: CityOptions,
             jobs: list[StreetJob] | None = None) -> dict:  # fmt: skip
    """Run (or resume) the city into ``out_dir``; returns city.json's dict plus "counts" and "files".

    Parameters
    ----------
    city : the validated city file (``citysim.city.spec.load_city``)
    city_file : its path (street files are relative to it)
    out_dir : the city folder (new, empty, or an earlier run of the same city, resumed)
    options : controllers, sample length, fidelity, ranking threshold, cluster (``CityOptions``)
    jobs : the prepared streets (default: ``city_jobs``)
    """
    jobs = jobs if jobs is not None else city_jobs(city, city_file, out_dir, options)
    counts = run_streets(jobs, out_dir, scheduler=options.scheduler, workers=options.workers,
                         progress=options.progress, cache_dir=options.cache_dir)  # fmt: skip
    years = [json.loads((street_dir(out_dir, job.name) / "year.json").read_text()) for job in jobs]
    result = city_result(city_name(city, city_file), jobs, years, options.min_lit_on_entry, str(city_file))
    result["sensor_models"] = shared_models(jobs)
    files = write_city(out_dir, result)
    return {**result, "counts": counts, "files": [str(f) for f in files]}
