"""Sweep scaling benchmark: the same 16-point sweep on 1 and on 2 local Dask workers.

Figures, never pass/fail. Each point is a tiny scenario (3 lamps on a 90 m
street, 60 simulated seconds, always-on and PIR controllers, no camera) so the
benchmark takes about a minute; the wall times include starting the local
cluster, as a user's sweep would.
"""

from __future__ import annotations

import csv
import os
import tempfile
import time
from pathlib import Path

import yaml

from citysim.sweep.runner import run_sweep

__all__ = ["bench_sweep_scaling", "main"]

REPO = Path(__file__).resolve().parents[2]

BENCH_SCENARIO = {
    "name": "bench_tiny",
    "seed": 5,
    "duration_s": 60,
    "street": {
        "length_m": 90,
        "lanes": [
            {"y_center_m": -1.6, "width_m": 3.2, "direction": 1},
            {"y_center_m": 1.6, "width_m": 3.2, "direction": -1},
        ],
        "sidewalks": [{"y_center_m": -4.3, "width_m": 2.2}, {"y_center_m": 4.3, "width_m": 2.2}],
        "crossings_x_m": [45],
    },
    "lamps": {
        "count": 3, "spacing_m": 30, "first_x_m": 15, "y_m": 6.2, "pole_height_m": 5.5,
        "camera": {"file": str(REPO / "scenarios" / "cameras" / "scene_a.yaml"), "tilt_deg": 15},
    },
    "traffic": {"classes": {"pedestrian": {"rate_per_hour": 300}, "vehicle": {"rate_per_hour": 150},
                            "cyclist": {"rate_per_hour": 40}}},
    "controllers": ["always_on", "pir"],
}  # fmt: skip

BENCH_SWEEP = {
    "name": "bench_scaling",
    "base": "bench_tiny.yaml",
    "seeds": [1],
    "axes": {"lamps.spacing_m": [24, 26, 28, 30], "traffic_density": [0.5, 1.0, 1.5, 2.0]},
    "save_objects": False,
}


def bench_sweep_scaling() -> dict:
    """Wall time of a 16-point sweep on 1 worker and on 2; returns the times and their ratio."""
    print("== sweep: 16 points on 1 vs 2 local Dask workers ==")
    out: dict = {"points": 16, "cpus": os.cpu_count()}
    with tempfile.TemporaryDirectory(prefix="citysim-sweep-bench-") as tmp:
        folder = Path(tmp)
        (folder / "bench_tiny.yaml").write_text(yaml.safe_dump(BENCH_SCENARIO))
        sweep_file = folder / "sweep.yaml"
        sweep_file.write_text(yaml.safe_dump(BENCH_SWEEP))
        for workers in (1, 2):
            t0 = time.perf_counter()
            counts = run_sweep(
                sweep_file, folder / f"out_{workers}", workers=workers, progress=False
            )
            wall_s = time.perf_counter() - t0
            if counts["ok"] != 16:
                raise RuntimeError(f"sweep benchmark: {counts['failed']} of 16 points failed")
            out[f"wall_s_{workers}_worker{'s' if workers > 1 else ''}"] = wall_s
        same = _rows(folder / "out_1") == _rows(folder / "out_2")
    out["speedup"] = out["wall_s_1_worker"] / out["wall_s_2_workers"]
    out["rows_match"] = same
    print(f"1 worker {out['wall_s_1_worker']:.1f} s   2 workers {out['wall_s_2_workers']:.1f} s   "
          f"speedup {out['speedup']:.2f}x   rows identical: {same}   "
          f"({out['cpus']} CPUs; wall times include cluster start-up)")  # fmt: skip
    return out


def _rows(folder: Path) -> set[tuple]:
    """The results without the timing columns (which differ run to run by nature)."""
    with open(folder / "results.csv", newline="") as f:
        return {
            tuple(sorted((k, v) for k, v in r.items() if k not in ("finished_at", "wall_s")))
            for r in csv.DictReader(f)
        }


def main() -> dict:
    return bench_sweep_scaling()


if __name__ == "__main__":
    main()
