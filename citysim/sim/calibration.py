"""Calibrate a scenario's sensor model (``citysim.fast``) from full-fidelity render-and-detect.

``calibrate`` runs the scenario's street, cameras and environment in full fidelity under
``CALIBRATION_CONTROLLER`` on seeds set aside for it (validation never uses them), records what
the real detector did with every candidate (``citysim.fast.records``), fits the model and caches
it in ``cache_dir`` under a hash of what it depends on: the placed cameras and poles, the street
and its scenery, the environment, the dim level, the idle-frame stride, the traffic kinds, the
detector's model file and the calibration settings. ``sensor_model_for`` loads the cached model,
else the one shipped in the repository (``SHIPPED_DIR``, same name and key, so ``make demo`` and a
fresh clone need no calibration), else calibrates. A shipped model is data, never refitted;
``tests/citysim/fast/test_shipped_models.py`` fails as soon as its key no longer matches its scenario.

Two kinds of nights, ``runs`` of each, ``duration_s`` long, at ``TRAFFIC_FACTOR`` times the
scenario's target traffic (more people per rendered frame):

* busy nights (seeds ``CALIBRATION_SEED_BASE + i``): the calibration controller lights the lamps
  as it would; with that much traffic nearly everyone is seen under lit lamps;
* quiet nights (seeds ``QUIET_SEED_BASE + i``): the same, but every lamp is held dim
  (``run_controller(lamps_held_dim=True)``). In the quiet hours, where adaptive lighting earns
  most, people arrive under dim lamps, and busy nights hardly show that: with busy nights alone
  (model v14) calibration saw 4 cars coming toward a camera under dim lamps, fast mode's
  ``detector_located`` lit 68 % of zone entries on entry at 02:00 (seed 2) where full fidelity
  lit 95.5 %, and with quiet nights added 95.5 % (README, "Fast mode").
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import multiprocessing as mp
import queue
from pathlib import Path

from tqdm import tqdm

from citysim.config.kinds import TARGET_KINDS
from citysim.config.scenario import ControllerSpec, Scenario, override
from citysim.fast.geometry import CameraGeometry
from citysim.fast.model import MODEL_VERSION, SensorModel, fit_sensor_model
from citysim.fast.records import CalibrationRecorder, RecordingSensors, merge_columns
from citysim.sim.loop import run_controller
from citysim.sim.workers import spawn_pool
from citysim.world.street import build_street

CALIBRATION_CONTROLLER = "detector_confirmed"
#: Calibration's busy nights use seeds CALIBRATION_SEED_BASE + i, its quiet nights (every lamp
#: held dim) QUIET_SEED_BASE + i: far from any scenario's own seed.
CALIBRATION_SEED_BASE = 900_000_000
QUIET_SEED_BASE = CALIBRATION_SEED_BASE + 100
DEFAULT_DURATION_S = 120.0
DEFAULT_RUNS = 2
#: Calibration nights carry this many times the scenario's target traffic: more candidates per
#: rendered frame (a rendered second costs the same with 3 people in view as with 1). It crowds
#: the street a little more than the scenario does; validation is where that would show.
TRAFFIC_FACTOR = 3.0


def default_cache_dir() -> Path:
    """``.cache/sensor_models`` in the project folder (git ignores it)."""
    return Path(__file__).resolve().parents[2] / ".cache" / "sensor_models"


#: Calibrated models committed with the repository, found when the cache has none of that key.
SHIPPED_DIR = Path(__file__).resolve().parents[2] / "scenarios" / "sensor_models"


def calibration_seeds(runs: int) -> list[tuple[int, bool]]:
    """(seed, lamps held dim) of each calibration night: ``runs`` busy nights, then ``runs`` quiet ones."""
    return [(CALIBRATION_SEED_BASE + i, False) for i in range(runs)] + [(QUIET_SEED_BASE + i, True) for i in range(runs)]


def general_model_path() -> Path:
    """``detector.general_model.GENERAL_MODEL_PATH``, found without importing that module: it
    imports scikit-learn (about 2 CPU-s), which a fast-mode run otherwise never needs."""
    spec = importlib.util.find_spec("detector.general_model")
    return Path(spec.origin).parent / "models" / "general.joblib"


def calibration_key(scenario: Scenario, duration_s: float, runs: int) -> str:
    """A hash of everything the sensor model depends on (not the traffic's rates, not the seed)."""
    street = build_street(scenario)
    parts = {
        "version": MODEL_VERSION,
        "cameras": [site.camera.model_dump(mode="json") for site in street.lamps],
        "poles": [[site.x_m, site.y_m, site.pole_height_m] for site in street.lamps],
        "street": scenario.street.model_dump(mode="json"),
        "environment": scenario.environment.model_dump(mode="json"),
        "dim_level": scenario.lamps.luminaire.dim_level,
        "idle_frame_stride": scenario.simulation.idle_frame_stride,
        "kinds": sorted(scenario.traffic.reported_kinds()),
        "detector_model_sha256": hashlib.sha256(general_model_path().read_bytes()).hexdigest(),
        "calibration": {"duration_s": duration_s, "runs": runs, "controller": CALIBRATION_CONTROLLER,
                        "nights": calibration_seeds(runs), "region_sizes_from": "busy nights"},
    }
    return hashlib.sha256(json.dumps(parts, sort_keys=True, default=str).encode()).hexdigest()[:16]


def model_path(scenario: Scenario, cache_dir: Path | None, duration_s: float, runs: int) -> Path:
    folder = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    return folder / f"{scenario.name}-{calibration_key(scenario, duration_s, runs)}.json"


def calibration_scenario(scenario: Scenario, seed: int, duration_s: float) -> Scenario:
    """The scenario on a calibration seed, ``TRAFFIC_FACTOR`` times its target traffic."""
    classes = scenario.traffic.classes
    updates = {f"traffic.classes.{kind}.rate_per_hour": getattr(classes, kind).rate_per_hour * TRAFFIC_FACTOR
               for kind in TARGET_KINDS}  # fmt: skip
    return override(scenario, {"seed": seed, "duration_s": duration_s, **updates})


def record_run(scenario: Scenario, seed: int, duration_s: float, on_progress=None, lamps_held_dim: bool = False):
    """One full-fidelity calibration night: its candidate rows and judged-frame rows."""
    night_scenario = calibration_scenario(scenario, seed, duration_s)
    street = build_street(night_scenario)
    sensors = RecordingSensors()
    recorder = CalibrationRecorder(CameraGeometry(street), sensors, street.lamps[0].camera.fps)
    run_controller(night_scenario, ControllerSpec(name=CALIBRATION_CONTROLLER), sensors=sensors,
                   observers=[recorder], on_progress=on_progress, lamps_held_dim=lamps_held_dim)  # fmt: skip
    return recorder.columns()


def calibrate(scenario: Scenario, cache_dir: Path | None = None, *, duration_s: float = DEFAULT_DURATION_S,
              runs: int = DEFAULT_RUNS, progress: bool = True, workers: int = 2) -> tuple[SensorModel, Path]:  # fmt: skip
    """Render-and-detect ``runs`` calibration nights, fit the sensor model, cache it; (model, path)."""
    path = model_path(scenario, cache_dir, duration_s, runs)
    bar = tqdm(total=duration_s * 2 * runs, unit="sim s", desc=f"calibrating {scenario.name} (full fidelity)",
               disable=not progress, bar_format="{l_bar}{bar}| {n:.0f}/{total:.0f} sim s [{elapsed}<{remaining}]")
    parts = _record_runs(scenario, duration_s, runs, workers, bar)
    bar.close()
    rows = merge_columns([p[0] for p in parts])
    frames = merge_columns([p[1] for p in parts])
    busy_frames = merge_columns([p[1] for p, (_, held_dim) in zip(parts, calibration_seeds(runs), strict=True)
                                 if not held_dim])  # fmt: skip
    camera_hours = duration_s * len(parts) * len(build_street(scenario).lamps) / 3600.0
    # the threshold baselines' region sizes from the busy nights: such a baseline lights its lamp as
    # soon as something big moves, so nobody crosses its view in the dark as on the quiet nights
    model = fit_sensor_model(rows, frames, camera_hours, key=path.stem,
                             idle_frame_stride=scenario.simulation.idle_frame_stride, area_frames=busy_frames)
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
    scenario, (seed, held_dim), duration_s, progress_queue = args
    return record_run(scenario, seed, duration_s, on_progress=progress_queue.put if progress_queue else None,
                      lamps_held_dim=held_dim)  # fmt: skip


def _record_runs(scenario: Scenario, duration_s: float, runs: int, workers: int, bar) -> list:
    """The calibration nights, in parallel processes when ``workers`` > 1 (results in seed order)."""
    seeds = calibration_seeds(runs)
    if workers <= 1:
        return [record_run(scenario, seed, duration_s, on_progress=bar.update, lamps_held_dim=held_dim)
                for seed, held_dim in seeds]  # fmt: skip
    with mp.Manager() as manager:
        q = manager.Queue()
        with spawn_pool(min(workers, len(seeds))) as pool:
            futures = [pool.submit(_record_worker, (scenario, seed, duration_s, q)) for seed in seeds]
            while not all(f.done() for f in futures):
                try:
                    bar.update(q.get(timeout=0.2))
                except queue.Empty:
                    pass
            return [f.result() for f in futures]
