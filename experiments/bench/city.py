"""City benchmark: one city's year on 1 and on 2 local Dask workers (wall, CPU, per-worker peak memory).

Figures, never pass/fail. The city is the shipped suburban_night and two
streets the bench derives from it (a longer one with 15 lamps, a shorter and busier one with 7),
at suburban_night's site, in fast mode with always-on, the oracle, PIR and detector_located, at a
reduced ``sample_s`` (the year's table measures that long per traffic level), so the bench takes
minutes rather than a real city's hours. All three share suburban_night's camera and environment,
hence one sensor model: the shipped one, found before the timed runs (no calibration). Wall times include starting
the local cluster, as a user's run would. CPU is the streets' tasks' process time (workers) plus
the client's. Per worker, the peak RSS after each of its streets, in order: flat means a worker
does not grow from street to street.
"""

from __future__ import annotations

import argparse
import copy
import json
import tempfile
import time
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[2]
#: (name, street length m, lamps, traffic multiplier) of the bench's streets; the first is suburban_night.
STREETS = (("suburban_night", 390.0, 11, 1.0), ("suburban_long", 510.0, 15, 0.8), ("suburban_busy", 240.0, 7, 2.0))
CONTROLLERS = ("always_on", "oracle", "pir", "detector_located")
SITE = {"latitude_deg": 52.52, "longitude_deg": 13.405, "timezone": "Europe/Berlin", "year": 2025}


def write_bench_city(folder: Path) -> Path:
    """The three streets' scenario files and CITY.yaml listing them in ``folder``; the city file's path."""
    from citysim.config.kinds import TARGET_KINDS

    base = yaml.safe_load((REPO / "scenarios" / "suburban_night.yaml").read_text())
    base["lamps"]["camera"]["file"] = str(REPO / "scenarios" / base["lamps"]["camera"]["file"])
    files = []
    for name, length_m, lamps, factor in STREETS:
        data = copy.deepcopy(base)
        data["name"], data["street"]["length_m"], data["lamps"]["count"] = name, length_m, lamps
        data["street"]["crossings_x_m"] = [x for x in data["street"]["crossings_x_m"] if x < length_m - 20]
        for kind, spec in data["traffic"]["classes"].items():
            if kind in TARGET_KINDS and "rate_per_hour" in spec:  # animals belong to the environment
                spec["rate_per_hour"] *= factor
        (folder / f"{name}.yaml").write_text(yaml.safe_dump(data))
        files.append(f"{name}.yaml")
    path = folder / "bench_city.yaml"
    path.write_text(yaml.safe_dump({"name": "bench_city", "site": SITE, "streets": files}))
    return path


def worker_figures(out_dir: Path, names: list[str]) -> tuple[float, dict[int, list[float]]]:
    """(CPU seconds of the streets' tasks, per worker pid its peak RSS MB after each street, in order)."""
    tasks = [json.loads((out_dir / "streets" / n / "task.json").read_text()) for n in names]
    peaks: dict[int, list[float]] = {}
    for task in sorted(tasks, key=lambda t: t["finished_unix_s"]):  # each worker's streets in the order run
        peaks.setdefault(task["pid"], []).append(round(task["worker_peak_rss_mb"], 1))
    return sum(t["cpu_s"] for t in tasks), peaks


def bench_city(sample_s: float = 120.0, worker_counts: tuple[int, ...] = (1, 2)) -> dict:
    """The bench city's year on each worker count; wall, CPU, per-worker peaks, speed-up, same city.json."""
    from citysim.city.models import city_models
    from citysim.city.run import CityOptions, city_jobs, run_city
    from citysim.city.spec import load_city

    print(f"== city: {len(STREETS)} streets' years (fast, sample_s {sample_s:g} s, "
          f"{', '.join(CONTROLLERS)}) on 1 vs 2 local Dask workers ==")  # fmt: skip
    out: dict = {"streets": len(STREETS), "sample_s": sample_s}
    with tempfile.TemporaryDirectory(prefix="citysim-city-bench-") as tmp:
        city_file = write_bench_city(Path(tmp))
        city = load_city(city_file)
        options = CityOptions(controllers=CONTROLLERS, sample_s=sample_s, progress=False, min_lit_on_entry=0.99)
        jobs = city_jobs(city, city_file, Path(tmp), options)
        t0 = time.perf_counter()
        keys, _ = city_models(jobs, progress=True)
        out["models"] = len(set(keys.values()))
        out["model_lookup_or_calibration_s"] = time.perf_counter() - t0
        texts = []
        for workers in worker_counts:
            folder = Path(tmp) / f"out_{workers}"
            t0, c0 = time.perf_counter(), time.process_time()
            run_city(city, city_file, folder, CityOptions(**{**vars(options), "workers": workers}), jobs=jobs)
            wall_s, client_cpu_s = time.perf_counter() - t0, time.process_time() - c0
            task_cpu_s, peaks = worker_figures(folder, [j.name for j in jobs])
            out[workers] = {"wall_s": wall_s, "cpu_s": task_cpu_s + client_cpu_s, "worker_peak_rss_mb": peaks}
            texts.append((folder / "city.json").read_text())
            print(f"{workers} worker{'s' if workers > 1 else ' '}: wall {wall_s:6.1f} s   CPU {task_cpu_s + client_cpu_s:6.1f} s"
                  f"   per-worker peak RSS after each street (MB): {list(peaks.values())}")  # fmt: skip
    if len(worker_counts) == 2:
        one, two = (out[w]["wall_s"] for w in worker_counts)
        out["speedup"] = one / two
        out["scaling_of_linear"] = out["speedup"] / (worker_counts[1] / worker_counts[0])
        out["same_city_json"] = texts[0] == texts[1]
        print(f"speed-up {out['speedup']:.2f}x ({100 * out['scaling_of_linear']:.0f} % of linear)   city.json identical: "
              f"{out['same_city_json']}   sensor models: {out['models']} (found or calibrated in "
              f"{out['model_lookup_or_calibration_s']:.1f} s before the timed runs)")  # fmt: skip
    return out


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(prog="python -m experiments.bench.city", description=__doc__.split("\n")[0])
    parser.add_argument("--sample-s", type=float, default=120.0, help="simulated seconds per traffic level")
    return bench_city(parser.parse_args(argv).sample_s)


if __name__ == "__main__":
    main()
