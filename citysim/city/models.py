"""Sensor models shared by streets: calibrated once per distinct camera and environment.

Fast fidelity's sensor model (``citysim.fast``) describes what the detector does with a road
user at a given forward distance, bearing, speed and light *relative to the camera*: it depends
on the camera (intrinsics, height, tilt, heading relative to the street, frame rate; the
scenario's ``lamps.camera`` with its file), the environment (light, weather, noise,
insects) and the lamps' dim level, not on where the street runs. ``camera_key`` hashes exactly
those (plus the traffic kinds the detector reports, the idle-frame stride, the detector's model
file and the model version), so streets that share it share one model. ``city_models`` finds,
for each key, a model already calibrated for any of its streets (the cache, then the shipped
models, under ``citysim.sim.calibration``'s per-street key) and calibrates the first street of
the key only when none of them has one.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence

from citysim.city.streets import StreetJob
from citysim.fast.model import MODEL_VERSION, SensorModel
from citysim.sim.calibration import (
    DEFAULT_DURATION_S,
    DEFAULT_RUNS,
    SHIPPED_DIR,
    general_model_path,
    model_path,
    sensor_model_for,
)


def camera_key(job: StreetJob) -> str:
    """A hash of what a street's sensor model depends on apart from the street's geometry."""
    scenario = job.scenario
    camera = scenario.lamps.camera
    parts = {
        "version": MODEL_VERSION,
        # intrinsics, height, tilt, heading relative to the street, frame rate; not where poles stand
        "camera": scenario.lamps.camera_model.model_dump(mode="json", exclude={"x_m", "y_m"}),
        "headings_deg": [camera.headings_deg, camera.back_heading_deg],
        "environment": scenario.environment.model_dump(mode="json"),
        "dim_level": scenario.lamps.luminaire.dim_level,
        "idle_frame_stride": scenario.simulation.idle_frame_stride,
        "kinds": sorted(scenario.traffic.reported_kinds()),
        "detector_model_sha256": hashlib.sha256(general_model_path().read_bytes()).hexdigest(),
    }  # fmt: skip
    return hashlib.sha256(json.dumps(parts, sort_keys=True, default=str).encode()).hexdigest()[:16]


def needs_model(job: StreetJob) -> bool:
    """Whether the street's year runs a camera controller at fast fidelity."""
    from citysim.sim.compare import needs_sensor_model, resolve_controllers

    specs = resolve_controllers(job.scenario, list(job.controllers) if job.controllers else None)
    return job.fidelity == "fast" and needs_sensor_model(specs)


def calibrated_model(job: StreetJob, cache_dir=None) -> SensorModel | None:
    """The street's own calibrated model (cache, then shipped) if there is one; never calibrates."""
    path = model_path(job.scenario, cache_dir, DEFAULT_DURATION_S, DEFAULT_RUNS)
    for candidate in (path, SHIPPED_DIR / path.name):
        if candidate.exists():
            try:
                return SensorModel.load(candidate)
            except (ValueError, KeyError, TypeError):
                continue
    return None


def city_models(jobs: Sequence[StreetJob], cache_dir=None, progress: bool = True) -> tuple[dict[str, str],
                                                                                          dict[str, SensorModel]]:
    """(street name -> camera key, camera key -> model) for the streets that need a model; each key's
    model is one already calibrated for one of its streets, else calibrated now on its first street."""
    keys = {job.name: camera_key(job) for job in jobs if needs_model(job)}
    models: dict[str, SensorModel] = {}
    for key in dict.fromkeys(keys.values()):
        members = [job for job in jobs if keys.get(job.name) == key]
        found = next((m for m in (calibrated_model(job, cache_dir) for job in members) if m is not None), None)
        models[key] = found if found is not None else sensor_model_for(members[0].scenario, cache_dir,
                                                                      progress=progress)  # fmt: skip
    return keys, models
