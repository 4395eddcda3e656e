"""Run every controller of a comparison on the same night and write the run folder.

Each controller is an independent simulation of the same scenario and seed,
so they can run in parallel processes (``workers``); the traffic they see is
identical because no random stream depends on the controller. The run folder
is staged and moved into place only when every controller finished:

    DIR/summary.json   figures per controller (see README)
    DIR/objects.csv    one row per object and lamp zone it crossed
    DIR/lamps.csv      level and power of every lamp, every simulated second
"""

from __future__ import annotations

import csv
import json
import multiprocessing as mp
import os
import queue
import shutil
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from tqdm import tqdm

from citysim.config.scenario import ControllerSpec, Scenario
from citysim.control.registry import CONTROLLERS
from citysim.metrics.crossings import OBJECTS_CSV_HEADER
from citysim.metrics.lamp_log import LAMPS_CSV_HEADER
from citysim.sim.calibration import sensor_model_for
from citysim.sim.loop import check_controllers, check_fidelity, controller_spec, run_controller
from citysim.world.coverage import camera_coverage
from citysim.world.street import build_street
from detector.outdir import staged_output

#: Every comparison holds these (savings are against always-on, and against the oracle's bound,
#: measured on the same night), first, in this order.
REFERENCE_CONTROLLERS = ("always_on", "oracle")


def resolve_controllers(scenario: Scenario, names: Sequence[str] | None) -> list[ControllerSpec]:
    """The specs to run: the scenario's own list, or the names given, with always_on and the
    oracle first whether named or not."""
    specs = list(scenario.controllers) if not names else [controller_spec(scenario, n) for n in names]
    check_controllers([s.name for s in specs])
    for position, name in enumerate(REFERENCE_CONTROLLERS):
        if not any(s.name == name for s in specs):
            specs.insert(position, ControllerSpec(name=name))
    return specs


def needs_sensor_model(specs: Sequence[ControllerSpec]) -> bool:
    """Whether any controller watches cameras (the others run alike in fast and full fidelity)."""
    return any(CONTROLLERS[s.name].uses_camera for s in specs)


def with_savings_vs_oracle(results: dict[str, dict]) -> dict[str, dict]:
    """Each controller's savings as a share of the oracle's (1: as much as the bound, None without
    an oracle or when the oracle saves nothing), placed after ``savings_vs_always_on``."""
    oracle = next((r for r in results.values() if r["controller"] == "oracle"), None)
    bound = oracle["savings_vs_always_on"] if oracle else None
    out = {}
    for label, result in results.items():
        share = result["savings_vs_always_on"] / bound if bound else None
        ordered = {}
        for key, value in result.items():
            ordered[key] = value
            if key == "savings_vs_always_on":
                ordered["savings_vs_oracle"] = share
        out[label] = ordered
    return out


def run_to_files(scenario: Scenario, spec: ControllerSpec, part_dir: Path, on_progress=None, fidelity: str = "full",
                 sensor_model=None) -> dict:  # fmt: skip
    """One controller's run writing its part of lamps.csv / objects.csv into ``part_dir``."""
    part_dir.mkdir(parents=True, exist_ok=True)
    label = spec.display_name
    with open(part_dir / f"{label}.lamps.csv", "w", newline="") as lf, \
            open(part_dir / f"{label}.objects.csv", "w", newline="") as of:  # fmt: skip
        return run_controller(scenario, spec, lamps_writer=csv.writer(lf), objects_writer=csv.writer(of),
                              on_progress=on_progress, fidelity=fidelity, sensor_model=sensor_model)


def _worker(args):
    scenario, spec, part_dir, progress_queue, fidelity, sensor_model = args
    last = [0.0]

    def report(dt_s: float) -> None:
        last[0] += dt_s
        if progress_queue is not None and last[0] >= 5.0:
            progress_queue.put(last[0])
            last[0] = 0.0

    summary = run_to_files(scenario, spec, Path(part_dir), on_progress=report, fidelity=fidelity,
                           sensor_model=sensor_model)
    if progress_queue is not None and last[0] > 0:
        progress_queue.put(last[0])
    return spec.display_name, summary


def run_comparison(
    scenario: Scenario,
    controllers: Sequence[str] | None = None,
    *,
    progress: bool = False,
    out_dir: Path | None = None,
    workers: int = 1,
    scenario_file: str | None = None,
    fidelity: str = "full",
    sensor_model=None,
    cache_dir: Path | None = None,
) -> dict:
    """Run the controllers; return the summary.json dict and, with ``out_dir``, write the run folder
    (summary.json, objects.csv, lamps.csv; the plots are drawn by ``citysim.report`` from these).

    ``fidelity`` "fast": cameras judged by the scenario's sensor model (``sensor_model``, else the
    one cached in ``cache_dir``, calibrated first if there is none; see ``citysim.sim.calibration``).
    """
    specs = resolve_controllers(scenario, controllers)
    check_fidelity(fidelity)
    if fidelity == "fast" and sensor_model is None and needs_sensor_model(specs):
        sensor_model = sensor_model_for(scenario, cache_dir, progress=progress)
    workers = max(1, min(workers, len(specs)))
    summary = {"scenario": scenario.name, "scenario_file": scenario_file, "seed": scenario.seed,
               "duration_s": scenario.duration_s, "fidelity": fidelity, "lamps": None,
               "coverage": camera_coverage(build_street(scenario)).as_dict(), "controllers": {}}
    with staged_output(out_dir) if out_dir is not None else _scratch() as stage:
        parts = stage / ".parts"
        total_s = scenario.duration_s * len(specs)
        bar = tqdm(total=total_s, unit="sim s", desc=f"{scenario.name}: {len(specs)} controllers", disable=not progress,
                   bar_format="{l_bar}{bar}| {n:.0f}/{total:.0f} sim s [{elapsed}<{remaining}, {rate_fmt}]")
        results: dict[str, dict] = {}
        if workers == 1:
            for spec in specs:
                results[spec.display_name] = run_to_files(scenario, spec, parts, on_progress=bar.update,
                                                          fidelity=fidelity, sensor_model=sensor_model)
        else:
            with mp.Manager() as manager:
                q = manager.Queue()
                ctx = mp.get_context("spawn")  # fresh interpreters: no forked OpenCV/pymunk state
                with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
                    # camera controllers first: the cheap ones fill the gaps at the end
                    heavy_first = sorted(specs, key=lambda s: not CONTROLLERS[s.name].uses_camera)
                    futures = [pool.submit(_worker, (scenario, spec, str(parts), q, fidelity, sensor_model))
                               for spec in heavy_first]  # fmt: skip
                    pending = set(futures)
                    while pending:
                        try:
                            bar.update(q.get(timeout=0.2))
                        except queue.Empty:
                            pass
                        for f in [f for f in pending if f.done()]:
                            pending.discard(f)
                            label, result = f.result()
                            results[label] = result
                    while not q.empty():
                        bar.update(q.get())
        bar.close()
        results = with_savings_vs_oracle({spec.display_name: results[spec.display_name] for spec in specs})
        summary["controllers"] = results
        summary["lamps"] = scenario.lamps.count or len(scenario.lamps.positions_x_m)
        _merge_parts(parts, [s.display_name for s in specs], stage)
        shutil.rmtree(parts, ignore_errors=True)
        (stage / "summary.json").write_text(json.dumps(summary, indent=2))
    return summary


def _merge_parts(parts: Path, labels: list[str], stage: Path) -> None:
    for kind, header in (("lamps", LAMPS_CSV_HEADER), ("objects", OBJECTS_CSV_HEADER)):
        with open(stage / f"{kind}.csv", "w", newline="") as out:
            csv.writer(out).writerow(header)
            for label in labels:
                part = parts / f"{label}.{kind}.csv"
                if part.exists():
                    with open(part) as fh:
                        shutil.copyfileobj(fh, out)


class _scratch:
    """A throw-away staging folder when no run folder is wanted."""

    def __enter__(self) -> Path:
        import tempfile

        self._dir = Path(tempfile.mkdtemp(prefix="citysim-run-"))
        return self._dir

    def __exit__(self, *exc) -> None:
        shutil.rmtree(self._dir, ignore_errors=True)


def default_workers() -> int:
    return max(1, min(2, os.cpu_count() or 1))
