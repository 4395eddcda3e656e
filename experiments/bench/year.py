"""Year bench: ``citysim year`` of suburban_night in fast mode, every controller, on 2 workers.

Times the response table and the annual sums (``citysim.year``) exactly as the command runs them,
wall and CPU seconds, beside a reference figure (149 CPU-s, 77 s wall, for always_on, oracle,
pir and schedule).

Design: docs/design/modules.md (The year bench)
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from citysim.config.scenario import load_scenario
from citysim.year.plan import prepare_year, table_runs, year_spec
from citysim.year.run import run_year
from experiments.bench.night import SUBURBAN, cpu_s

BEFORE_CPU_S, REPLAYED_CPU_S, REPLAYED_WALL_S = 446.0, 149.0, 77.0
#: every controller, fast mode, before the savings of the module docstring
EVERY_CONTROLLER_BEFORE_CPU_S = 947.0
TARGET_WALL_S = 300.0


def bench_year(controllers: list[str] | None = None, workers: int = 2, scenario_path: Path = SUBURBAN) -> dict:
    """Wall and CPU seconds of one fast-mode year of ``controllers`` (default: the scenario's list)."""
    scenario = load_scenario(scenario_path)
    plan = prepare_year(scenario, year_spec(scenario, str(scenario_path)))
    runs, sim_s = table_runs(plan)
    n = len(controllers) if controllers else len(scenario.controllers)
    print(f"== year, fast mode: {scenario.name} {plan.year.year}, {n} controllers, {runs} hour-runs, "
          f"{sim_s:,.0f} sim s per controller in all, {workers} workers ==")
    with tempfile.TemporaryDirectory(prefix="bench-year-") as tmp:
        c0, t0 = cpu_s(), time.perf_counter()
        run_year(plan, Path(tmp) / "year", controllers, workers=workers, fidelity="fast", progress=True)
        wall, cpu = time.perf_counter() - t0, cpu_s() - c0
    print(f"one year, {n} controllers, fast mode, {workers} cores: {wall:.0f} s wall, {cpu:.0f} CPU-s; before: "
          f"{BEFORE_CPU_S:.0f} CPU-s (always_on, oracle, pir, schedule, each stepping its own world), "
          f"{REPLAYED_CPU_S:.0f} CPU-s / {REPLAYED_WALL_S:.0f} s wall with the traffic replayed; every "
          f"controller {EVERY_CONTROLLER_BEFORE_CPU_S:.0f} CPU-s before this round's fast-mode savings; "
          f"target <= {TARGET_WALL_S / 60:.0f} min")
    return {"controllers": n, "wall_s": wall, "cpu_s": cpu}
