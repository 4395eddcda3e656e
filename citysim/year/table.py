"""The hourly response table: what each controller does in one hour at a given traffic level.

One level run per traffic level (at the scenario's ``start_hour``, ``warmup_s`` then
``sample_s`` measured) and one idle run per clock hour that can be dark; each run is one
``citysim.sim.compare.run_comparison``. Figures are per hour (window totals x 3600 / window).

Design: docs/design/year-response-table.md
"""

from __future__ import annotations

import csv
import json
import shutil
import tempfile
from collections import defaultdict
from collections.abc import Sequence
from concurrent.futures import as_completed
from dataclasses import asdict, dataclass, field
from pathlib import Path

from citysim.config.scenario import Scenario, override
from citysim.config.year import YearSpec
from citysim.sim.calibration import sensor_model_for
from citysim.sim.compare import needs_sensor_model, resolve_controllers, run_comparison
from citysim.sim.progress import SimulatedTimeBar
from citysim.sim.workers import spawn_pool
from citysim.year.factors import target_classes

J_PER_KWH = 3.6e6
#: A walker's speed for the default warm-up (the time to walk the street end to end), m/s.
WARMUP_WALK_MPS = 1.3
FIGURES = ("energy_kwh", "zone_entries", "lit_entries", "dark_s")
#: An idle run's lamps settle (a schedule's lamps start full and fade in 1 s) before it is measured, s.
IDLE_SETTLE_S = 5.0


@dataclass(frozen=True)
class Cell:
    """One run of the table: a level run (traffic, at the reference hour) or an idle run (an hour)."""

    kind: str  # "level" | "idle"
    level: float  # multiple of every class's rate_per_hour (0 for idle runs)
    start_hour: float  # clock hour at t = 0
    warmup_s: float
    sample_s: float

    @property
    def duration_s(self) -> float:
        return self.warmup_s + self.sample_s


@dataclass
class ResponseTable:
    """Per-hour figures per controller: ``levels[L][label]`` and ``idle[hour][label]``, each a
    {figure: value per hour} mapping (figures: ``FIGURES``)."""

    reference_hour: int
    levels: dict[float, dict[str, dict[str, float]]]
    idle: dict[int, dict[str, dict[str, float]]]
    labels: list[str]
    cells: list[Cell]
    wall_s: float = 0.0
    #: per level run and controller, (zone entries, lit on entry) of each road user in its window:
    #: what the lit-on-entry interval resamples (``annual.lit_on_entry_interval``); not in year.json
    tallies: dict[float, dict[str, list[list[int]]]] = field(default_factory=dict)

    def as_dict(self) -> dict:
        return {"reference_hour": self.reference_hour, "labels": self.labels,
                "levels": {str(k): v for k, v in self.levels.items()},
                "idle": {str(k): v for k, v in self.idle.items()},
                "runs": [asdict(c) for c in self.cells], "wall_s": self.wall_s}  # fmt: skip


def default_warmup_s(scenario: Scenario, year: YearSpec) -> float:
    return year.warmup_s if year.warmup_s is not None else scenario.street.length_m / WARMUP_WALK_MPS


def plan_cells(scenario: Scenario, year: YearSpec, dark_hours: Sequence[int]) -> list[Cell]:
    """The table's runs, heaviest first (the busiest level runs, then the idle hours)."""
    warmup_s = default_warmup_s(scenario, year)
    levels = [Cell("level", lv, scenario.start_hour, warmup_s, year.sample_s)
              for lv in sorted(year.traffic_levels, reverse=True)]  # fmt: skip
    hours = sorted(set(dark_hours) | {int(scenario.start_hour)})
    idle = [Cell("idle", 0.0, float(h), IDLE_SETTLE_S, year.idle_sample_s) for h in hours]
    return levels + idle


def cell_variant(scenario: Scenario, cell: Cell) -> Scenario:
    """The scenario of one run: its clock hour and length, every class at the cell's level with a flat
    profile, no scripted test agents (they are not part of a typical hour)."""
    updates: dict = {"duration_s": cell.duration_s, "start_hour": cell.start_hour, "traffic.scripted": []}
    for name, spec in target_classes(scenario).items():
        updates[f"traffic.classes.{name}.rate_per_hour"] = spec.rate_per_hour * cell.level
        updates[f"traffic.classes.{name}.hourly_profile"] = []
    return override(scenario, updates)


def window_figures(folder: Path, labels: Sequence[str], t0_s: float,
                   t1_s: float) -> tuple[dict[str, dict[str, float]], dict[str, list[list[int]]]]:  # fmt: skip
    """Per-hour figures of each controller inside [t0_s, t1_s) from a run folder's CSVs: energy from
    lamps.csv (power sampled each second), entries, lit entries and dark seconds of the zone entries
    made inside the window from objects.csv; and, from the same rows, each road user's [zone entries,
    entries lit on entry] per controller (what the lit-on-entry interval resamples)."""
    totals = {label: dict.fromkeys(FIGURES, 0.0) for label in labels}
    tallies: dict[str, dict[str, list[int]]] = {label: {} for label in labels}
    with open(folder / "lamps.csv", newline="") as fh:
        for row in csv.DictReader(fh):
            if t0_s <= float(row["t_s"]) < t1_s:
                totals[row["controller"]]["energy_kwh"] += float(row["power_w"]) / J_PER_KWH  # 1 s each
    with open(folder / "objects.csv", newline="") as fh:
        for row in csv.DictReader(fh):
            if t0_s <= float(row["t_enter_s"]) < t1_s:
                t = totals[row["controller"]]
                lit = int(row["lit_on_entry"])
                t["zone_entries"] += 1
                t["lit_entries"] += lit
                t["dark_s"] += float(row["dark_s"] or 0.0)
                counts = tallies[row["controller"]].setdefault(row["object_id"], [0, 0])
                counts[0] += 1
                counts[1] += lit
    per_hour = 3600.0 / (t1_s - t0_s)
    figures = {label: {k: v * per_hour for k, v in figs.items()} for label, figs in totals.items()}
    return figures, {label: list(objects.values()) for label, objects in tallies.items()}


def run_cell(scenario: Scenario, cell: Cell, names: list[str] | None, fidelity: str,
             sensor_model=None) -> tuple[dict, dict]:  # fmt: skip
    """One run of the table (in a worker process): its per-hour figures per controller, and each
    road user's entries and lit entries (``window_figures``)."""
    variant = cell_variant(scenario, cell)
    folder = Path(tempfile.mkdtemp(prefix="citysim-year-")) / "run"
    try:
        summary = run_comparison(variant, names, workers=1, fidelity=fidelity, out_dir=folder,
                                 sensor_model=sensor_model)  # fmt: skip
        labels = list(summary["controllers"])
        return window_figures(folder, labels, cell.warmup_s, cell.duration_s)
    finally:
        shutil.rmtree(folder.parent, ignore_errors=True)


def build_table(scenario: Scenario, year: YearSpec, dark_hours: Sequence[int], names: list[str] | None = None,
                *, workers: int = 1, fidelity: str = "full", progress: bool = True,
                sensor_model=None) -> ResponseTable:
    """Run every cell (``workers`` processes) and gather the table; a bar shows simulated seconds
    done, their rate and the time left. ``sensor_model``: fast fidelity's model (default: the
    scenario's own, ``sensor_model_for``; a city shares one among streets of one camera)."""
    import time

    cells = plan_cells(scenario, year, dark_hours)
    specs = resolve_controllers(scenario, names)
    labels = [s.display_name for s in specs]
    cost = {c: c.duration_s * len(labels) for c in cells}
    bar = SimulatedTimeBar(sum(cost.values()), f"{scenario.name}: {len(cells)} hour-runs x {len(labels)} controllers",
                           disable=not progress)
    start = time.perf_counter()
    # the scenario's own sensor model for every cell: a cell's variant differs in traffic only, but an
    # idle cell (no traffic) lists fewer kinds, so looking its model up by its own key calibrated a
    # second model on empty nights (2 min on a fresh clone) that knew no road user
    model = None
    if fidelity == "fast" and needs_sensor_model(specs):
        model = sensor_model if sensor_model is not None else sensor_model_for(scenario, progress=progress)
    results: dict[Cell, tuple[dict, dict]] = {}
    if workers <= 1:
        for cell in cells:
            results[cell] = run_cell(scenario, cell, names, fidelity, model)
            bar.update(cost[cell])
    else:
        with spawn_pool(workers) as pool:  # fresh interpreters, as run_comparison's own workers
            futures = {pool.submit(run_cell, scenario, c, names, fidelity, model): c for c in cells}
            for done in as_completed(futures):
                results[futures[done]] = done.result()
                bar.update(cost[futures[done]])
    bar.close()
    levels: dict[float, dict] = {}
    tallies: dict[float, dict] = {}
    idle: dict[int, dict] = defaultdict(dict)
    for cell in cells:  # in plan order, whatever order they finished in
        if cell.kind == "level":
            levels[cell.level], tallies[cell.level] = results[cell]
        else:
            idle[int(cell.start_hour)] = results[cell][0]
    return ResponseTable(int(scenario.start_hour), dict(sorted(levels.items())), dict(idle), labels, cells,
                         time.perf_counter() - start, dict(sorted(tallies.items())))


def load_table(path: Path) -> dict:
    return json.loads(Path(path).read_text())
