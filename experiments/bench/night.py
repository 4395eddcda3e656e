"""Whole-night bench: every controller of suburban_night through one comparison, on 2 workers.

``bench_night(duration_s)`` times ``citysim.sim.compare.run_comparison`` (the traffic recorded
once and replayed to every controller, as ``citysim run`` does) over the first ``duration_s``
simulated seconds of the night and prints the wall time beside the figure measured before the
traffic was replayed and the other costs cut: a whole night (22:00-06:00, 28,800 s) of every
controller took about 1.8 hours on 2 cores. A run shorter than the night also prints the
whole night scaled from it; the night starts with its busiest hour, so that is an upper bound.

``python -m experiments.bench --night`` runs the whole night (long); ``make bench`` a sample.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from citysim.config.scenario import load_scenario, override
from citysim.sim.compare import run_comparison

REPO = Path(__file__).resolve().parents[2]
WHOLE_NIGHT_S = 28_800.0
#: every controller of suburban_night, a whole night on 2 cores, before this bench existed
BEFORE_WHOLE_NIGHT_WALL_S = 1.8 * 3600.0
#: the run length ``make bench`` samples (the first 10 minutes: the busiest of the night)
SAMPLE_S = 600.0


def bench_night(duration_s: float = SAMPLE_S, workers: int = 2,
                scenario_path: Path = REPO / "scenarios" / "suburban_night.yaml") -> dict:  # fmt: skip
    """Wall seconds of every controller over ``duration_s`` on ``workers`` processes, and the
    whole night's wall time (measured, or scaled from the sample)."""
    if not 0 < duration_s <= WHOLE_NIGHT_S:
        raise ValueError(f"duration_s: must be in (0, {WHOLE_NIGHT_S:.0f}] s, got {duration_s}")
    scenario = override(load_scenario(scenario_path), {"duration_s": float(duration_s)})
    n = len(scenario.controllers)
    print(f"== whole night: {scenario.name}, {n} controllers, {duration_s:.0f} sim s, {workers} workers ==")
    with tempfile.TemporaryDirectory(prefix="bench-night-") as tmp:
        t0 = time.perf_counter()
        run_comparison(scenario, out_dir=Path(tmp) / "run", workers=workers, progress=True)
        wall_s = time.perf_counter() - t0
    night_s = wall_s * WHOLE_NIGHT_S / duration_s
    how = "measured" if duration_s >= WHOLE_NIGHT_S else f"scaled from the first {duration_s:.0f} s, an upper bound"
    print(f"{n} controllers x {duration_s:.0f} sim s: {wall_s:.0f} s wall ({duration_s * n / wall_s:.1f} sim s per wall s, "
          f"all controllers together)")
    print(f"whole night, every controller, {workers} cores: {night_s / 60:.1f} min ({how}); "
          f"before: {BEFORE_WHOLE_NIGHT_WALL_S / 3600:.1f} h; target <= 15 min")
    return {"duration_s": duration_s, "wall_s": wall_s, "whole_night_wall_s": night_s,
            "before_whole_night_wall_s": BEFORE_WHOLE_NIGHT_WALL_S}  # fmt: skip
