"""Calibrate a scenario's sensor model (``citysim.fast``) from full-fidelity render-and-detect.

``calibrate`` runs busy, quiet (lamps held dim) and region nights on seeds set aside for it,
fits the model and caches it under a hash of what it depends on; ``sensor_model_for`` loads
the cached model, else the shipped one (``SHIPPED_DIR``), else calibrates.

Design: docs/design/fast-mode-sensor-model.md
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import multiprocessing as mp
import queue
from pathlib import Path
from typing import NamedTuple

from citysim.config.kinds import TARGET_KINDS
from citysim.config.scenario import ControllerSpec, Scenario, override
from citysim.fast.geometry import CameraGeometry
from citysim.fast.model import MODEL_VERSION, SensorModel, fit_sensor_model
from citysim.fast.records import CalibrationRecorder, RecordingSensors, merge_columns
from citysim.fast.region_records import RegionRecorder, RegionSensors
from citysim.sim.loop import run_controller
from citysim.sim.progress import SimulatedTimeBar
from citysim.sim.workers import spawn_pool
from citysim.world.street import build_street

CALIBRATION_CONTROLLER = "detector_confirmed"
#: The threshold baselines whose region sizes fast mode draws: each drives region nights of its own.
THRESHOLD_CONTROLLERS = ("threshold_05", "threshold_5")
#: Calibration's busy nights use seeds CALIBRATION_SEED_BASE + i, its quiet nights (every lamp
#: held dim) QUIET_SEED_BASE + i, its region nights REGION_SEED_BASE + i: far from any scenario's seed.
CALIBRATION_SEED_BASE = 900_000_000
QUIET_SEED_BASE = CALIBRATION_SEED_BASE + 100
REGION_SEED_BASE = CALIBRATION_SEED_BASE + 300
DEFAULT_DURATION_S = 120.0
DEFAULT_RUNS = 2
#: Busy and quiet nights carry this many times the scenario's target traffic: more candidates per
#: rendered frame (a rendered second costs the same with 3 people in view as with 1). It crowds
#: the street a little more than the scenario does; validation is where that would show (it did
#: for the threshold baselines' region sizes, which therefore have region nights at 1x).
TRAFFIC_FACTOR = 3.0


class CalibrationNight(NamedTuple):
    """One calibration night: its seed, the controller switching its lamps, its traffic (times the
    scenario's target traffic) and whether every lamp is held dim."""

    seed: int
    controller: str
    traffic_factor: float
    lamps_held_dim: bool

    @property
    def records_regions(self) -> bool:
        """A region night: a threshold baseline's largest regions, not the detector's candidates."""
        return self.controller in THRESHOLD_CONTROLLERS


def default_cache_dir() -> Path:
    """``.cache/sensor_models`` in the project folder (git ignores it)."""
    return Path(__file__).resolve().parents[2] / ".cache" / "sensor_models"


#: Calibrated models committed with the repository, found when the cache has none of that key.
SHIPPED_DIR = Path(__file__).resolve().parents[2] / "scenarios" / "sensor_models"


def calibration_nights(runs: int) -> list[CalibrationNight]:
    """Every calibration night, in order: ``runs`` busy nights, ``runs`` quiet ones, then ``runs``
    region nights per threshold baseline (the same seeds for each: the same traffic, its own lamps)."""
    busy = [CalibrationNight(CALIBRATION_SEED_BASE + i, CALIBRATION_CONTROLLER, TRAFFIC_FACTOR, False) for i in range(runs)]
    quiet = [CalibrationNight(QUIET_SEED_BASE + i, CALIBRATION_CONTROLLER, TRAFFIC_FACTOR, True) for i in range(runs)]
    regions = [CalibrationNight(REGION_SEED_BASE + i, name, 1.0, False) for name in THRESHOLD_CONTROLLERS
               for i in range(runs)]  # fmt: skip
    return busy + quiet + regions


def general_model_path() -> Path:
    """``detector.general_model.GENERAL_MODEL_PATH``, found without importing that module: it
    imports scikit-learn (about 2 CPU-s), which a fast-mode run otherwise never needs."""
    spec = importlib.util.find_spec("detector.general_model")
    return Path(spec.origin).parent / "models" / "general.joblib"


def _street_key(scenario: Scenario) -> dict:
    """The street section as the key has it: the real-street fields (``config.street_layout``) only
    when given, so a straight street keeps the key (and the shipped models) it had without them."""
    street = scenario.street
    unset = {name for name in ("centreline_m", "origin", "source", "side_entries")
             if getattr(street, name) == type(street).model_fields[name].get_default(call_default_factory=True)}  # fmt: skip
    return street.model_dump(mode="json", exclude=unset)


def calibration_key(scenario: Scenario, duration_s: float, runs: int) -> str:
    """A hash of everything the sensor model depends on (not the traffic's rates, not the seed)."""
    street = build_street(scenario)
    parts = {
        "version": MODEL_VERSION,
        "cameras": [site.camera.model_dump(mode="json") for site in street.lamps],
        "poles": [[site.x_m, site.y_m, site.pole_height_m] for site in street.lamps],
        "street": _street_key(scenario),
        "environment": scenario.environment.model_dump(mode="json"),
        "dim_level": scenario.lamps.luminaire.dim_level,
        "idle_frame_stride": scenario.simulation.idle_frame_stride,
        "kinds": sorted(scenario.traffic.reported_kinds()),
        "detector_model_sha256": hashlib.sha256(general_model_path().read_bytes()).hexdigest(),
        "calibration": {"duration_s": duration_s, "runs": runs, "nights": calibration_nights(runs),
                        "region_sizes_from": "region nights"},
    }
    backs = [site.back_camera.model_dump(mode="json") for site in street.lamps if site.back_camera is not None]
    if backs:  # only then, so a one-camera-per-pole street keeps the key it had before backward cameras existed
        parts["back_cameras"] = backs
    return hashlib.sha256(json.dumps(parts, sort_keys=True, default=str).encode()).hexdigest()[:16]


def model_path(scenario: Scenario, cache_dir: Path | None, duration_s: float, runs: int) -> Path:
    folder = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    return folder / f"{scenario.name}-{calibration_key(scenario, duration_s, runs)}.json"


def calibration_scenario(scenario: Scenario, seed: int, duration_s: float, traffic_factor: float = TRAFFIC_FACTOR) -> Scenario:
    """The scenario on a calibration seed, ``traffic_factor`` times its target traffic."""
    classes = scenario.traffic.classes
    updates = {f"traffic.classes.{kind}.rate_per_hour": getattr(classes, kind).rate_per_hour * traffic_factor
               for kind in TARGET_KINDS}  # fmt: skip
    return override(scenario, {"seed": seed, "duration_s": duration_s, **updates})


def record_run(scenario: Scenario, night: CalibrationNight, duration_s: float, on_progress=None) -> tuple:
    """One full-fidelity calibration night: (candidate rows, judged-frame rows); a region night has
    no candidate rows (None) and frame rows of ``citysim.fast.region_records.REGION_COLUMNS``."""
    night_scenario = calibration_scenario(scenario, night.seed, duration_s, night.traffic_factor)
    street = build_street(night_scenario)
    fps = street.lamps[0].camera.fps
    if night.records_regions:
        sensors = RegionSensors()
        recorder = RegionRecorder(CameraGeometry(street), sensors, fps)
    else:
        sensors = RecordingSensors()
        recorder = CalibrationRecorder(CameraGeometry(street), sensors, fps)
    run_controller(night_scenario, ControllerSpec(name=night.controller), sensors=sensors, observers=[recorder],
                   on_progress=on_progress, lamps_held_dim=night.lamps_held_dim)  # fmt: skip
    return (None, recorder.region_columns()) if night.records_regions else recorder.columns()


def calibrate(scenario: Scenario, cache_dir: Path | None = None, *, duration_s: float = DEFAULT_DURATION_S,
              runs: int = DEFAULT_RUNS, progress: bool = True, workers: int = 2) -> tuple[SensorModel, Path]:  # fmt: skip
    """Render-and-detect the calibration nights, fit the sensor model, cache it; (model, path)."""
    path = model_path(scenario, cache_dir, duration_s, runs)
    nights = calibration_nights(runs)
    bar = SimulatedTimeBar(duration_s * len(nights), f"calibrating {scenario.name} (full fidelity)",
                           disable=not progress)
    parts = _record_runs(scenario, nights, duration_s, workers, bar)
    bar.close()
    detector_parts = [part for part, night in zip(parts, nights, strict=True) if not night.records_regions]
    rows = merge_columns([rows for rows, _ in detector_parts])
    frames = merge_columns([frames for _, frames in detector_parts])
    region_frames = merge_columns([frames for (_, frames), night in zip(parts, nights, strict=True)
                                   if night.records_regions])  # fmt: skip
    camera_hours = duration_s * len(detector_parts) * len(build_street(scenario).cameras) / 3600.0
    model = fit_sensor_model(rows, frames, camera_hours, key=path.stem,
                             idle_frame_stride=scenario.simulation.idle_frame_stride, area_frames=region_frames)
    model.save(path)
    return model, path


def sensor_model_for(scenario: Scenario, cache_dir: Path | None = None, *, duration_s: float = DEFAULT_DURATION_S,
                     runs: int = DEFAULT_RUNS, progress: bool = True, workers: int = 2) -> SensorModel:  # fmt: skip
    """The scenario's cached sensor model, else the shipped one of the same key, calibrated now (with a
    progress bar) if there is neither."""
    path = model_path(scenario, cache_dir, duration_s, runs)
    for candidate in (path, SHIPPED_DIR / path.name):
        if candidate.exists():
            try:
                return SensorModel.load(candidate)
            except (ValueError, KeyError, TypeError):
                pass  # another version or a damaged file: the next, else calibrate again
    return calibrate(scenario, cache_dir, duration_s=duration_s, runs=runs, progress=progress, workers=workers)[0]


def _record_worker(args):
    scenario, night, duration_s, progress_queue = args
    return record_run(scenario, night, duration_s, on_progress=progress_queue.put if progress_queue else None)


def _record_runs(scenario: Scenario, nights: list[CalibrationNight], duration_s: float, workers: int, bar) -> list:
    """The calibration nights, in parallel processes when ``workers`` > 1 (results in the nights' order)."""
    if workers <= 1:
        return [record_run(scenario, night, duration_s, on_progress=bar.update) for night in nights]
    with mp.Manager() as manager:
        q = manager.Queue()
        with spawn_pool(min(workers, len(nights))) as pool:
            futures = [pool.submit(_record_worker, (scenario, night, duration_s, q)) for night in nights]
            while not all(f.done() for f in futures):
                try:
                    bar.update(q.get(timeout=0.2))
                except queue.Empty:
                    pass
            return [f.result() for f in futures]
