"""The street-tracker measurements: every run of the fusion table, one result file each.

Runs ``always_on, oracle, oracle_seen, pir, detector_located, detector_fused`` on
suburban_night_two_way and suburban_night, seeds 1-3, 1,200 s from 22:00 and from 02:00 (hour 0
and hour 4 of the night, ``experiments.bench.night.night_hour``), in full fidelity and in fast
mode, and a whole fast night (22:00-06:00) of each scenario. Each run is written to
``experiments/results/fusion/<scenario>-<HHMM>-seed<N>-<fidelity>.json`` as soon as it ends; a run
whose file exists is skipped, so the command resumes after an interruption::

    python -m experiments.fusion_runs                  # everything (about 3 CPU-hours on 2 cores)
    python -m experiments.fusion_runs --fidelity fast  # the fast runs only (minutes)

``make results`` turns the files into the tables of docs/design/fusion.md.

Design: docs/design/fusion.md (Measurements)
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from citysim.city.runner import write_atomic
from citysim.config.scenario import Scenario, load_scenario, override
from citysim.sim.compare import run_comparison
from experiments.bench.night import WHOLE_NIGHT_S, cpu_s, night_hour
from experiments.results.sources import FUSION, RESULTS_DIR

REPO = Path(__file__).resolve().parents[1]
OUT_DIR = RESULTS_DIR / FUSION.file
SCENARIOS = ("suburban_night_two_way", "suburban_night")
CONTROLLERS = ("always_on", "oracle", "oracle_seen", "pir", "detector_located", "detector_fused")
SEEDS = (1, 2, 3)
#: hours of the night after its 22:00 start: 22:00 and 02:00
NIGHT_HOURS = (0, 4)
RUN_S = 1200.0
#: summary keys kept per controller (the rest of summary.json is per lamp or per hour)
KEPT_KEYS = ("energy_kwh", "savings_vs_always_on", "savings_vs_oracle", "gap_unseen", "gap_unused", "dark_unseen",
             "dark_unused", "lit_on_entry_rate", "zone_entries", "dark_s_per_100_entries", "lag_p95_s",
             "unlit_crossings", "false_on_time_s", "on_time_s", "per_class")  # fmt: skip


def start_clock(hour: int) -> str:
    """The clock time hour ``hour`` of the night (from 22:00) starts at: ``22:00``, ``02:00``."""
    return f"{(22 + hour) % 24:02d}:00"


def run_name(scenario: str, hour: int | None, seed: int, fidelity: str) -> str:
    """``<scenario>-<HHMM>-seed<N>-<fidelity>``; ``night`` for the whole night."""
    when = "night" if hour is None else start_clock(hour).replace(":", "")
    return f"{scenario}-{when}-seed{seed}-{fidelity}"


def night_of(base: Scenario, hour: int | None, seed: int) -> Scenario:
    """The run's scenario: hour ``hour`` of the night for RUN_S s, or the whole night."""
    night = override(base, {"duration_s": WHOLE_NIGHT_S}) if hour is None else night_hour(base, hour, RUN_S)
    return override(night, {"seed": seed})


def reduced(summary: dict) -> dict:
    """The kept figures of every controller of one summary."""
    return {label: {k: c.get(k) for k in KEPT_KEYS} for label, c in summary["controllers"].items()}


def measure(base: Scenario, hour: int | None, seed: int, fidelity: str, workers: int) -> dict:
    """One comparison; its figures with wall and CPU seconds."""
    scenario = night_of(base, hour, seed)
    c0, t0 = cpu_s(), time.perf_counter()
    summary = run_comparison(scenario, list(CONTROLLERS), workers=workers, fidelity=fidelity, progress=False)
    return {"scenario": base.name, "start_hour": scenario.start_hour, "seed": seed, "fidelity": fidelity,
            "duration_s": scenario.duration_s, "wall_s": round(time.perf_counter() - t0, 1),
            "cpu_s": round(cpu_s() - c0, 1), "controllers": reduced(summary)}  # fmt: skip


def planned_runs(fidelities: list[str], scenarios: list[str]) -> list[tuple[str, int | None, int, str]]:
    """(scenario, hour or None, seed, fidelity) of every run, the full-fidelity two-way runs first."""
    runs = [(name, hour, seed, fid) for fid in fidelities for name in scenarios for hour in NIGHT_HOURS
            for seed in SEEDS]  # fmt: skip
    if "fast" in fidelities:
        runs += [(name, None, SEEDS[0], "fast") for name in scenarios]
    return runs


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m experiments.fusion_runs", description=__doc__.split("\n\n")[0])
    parser.add_argument("--fidelity", choices=("full", "fast", "both"), default="both")
    parser.add_argument("--scenario", choices=SCENARIOS, action="append", help="default: both")
    parser.add_argument("--workers", type=int, default=2, help="processes per full-fidelity run")
    args = parser.parse_args(argv)
    fidelities = ["full", "fast"] if args.fidelity == "both" else [args.fidelity]
    runs = planned_runs(fidelities, args.scenario or list(SCENARIOS))
    for i, (name, hour, seed, fidelity) in enumerate(runs, 1):
        path = OUT_DIR / f"{run_name(name, hour, seed, fidelity)}.json"
        if path.exists():
            continue
        base = load_scenario(REPO / "scenarios" / f"{name}.yaml")
        result = measure(base, hour, seed, fidelity, args.workers if fidelity == "full" else 1)
        write_atomic(path, json.dumps(result, indent=1, sort_keys=True) + "\n")
        fused = result["controllers"]["detector_fused"]
        print(f"[{i}/{len(runs)}] {path.name}: {result['cpu_s']:.0f} CPU-s; detector_fused "
              f"{fused['savings_vs_oracle']} of the oracle's savings at {fused['lit_on_entry_rate']} lit on entry",
              flush=True)  # fmt: skip
    print(f"results in {OUT_DIR}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
