"""Straight against curved: the cost of the centreline, in simulated seconds per CPU second (fast mode).

suburban_night (390 m along +x, 11 lamps) against the same street bent 90 degrees half-way
(centreline (0, 0) -> (195, 0) -> (195, 195), the same length, lanes, lamps, cameras relative to
the street and traffic): every controller of the scenario in fast mode, ``sample_s`` simulated
seconds, on one worker, with the straight street's shipped sensor model for both (the cameras see
the same kind of street; the figure is the geometry's cost, not a calibration's). The runs
alternate (straight, curved, straight, curved ...) ``repeats`` times, and each street's fastest
run is its figure, so another job on the machine inflates neither more than the other. Target:
the curved street costs at most 10 % more per simulated second.
"""

from __future__ import annotations

from pathlib import Path

from citysim.config.scenario import Scenario, load_scenario, override
from citysim.sim.calibration import sensor_model_for
from experiments.bench.night import SUBURBAN, timed_comparison

#: the bend: half the street east, half north
BEND_AT_M = 195.0
#: the curved street may cost this much more per simulated second
TARGET_RATIO = 1.10


def bent(scenario: Scenario) -> Scenario:
    """``scenario``'s street bent 90 degrees to the left half-way along it (the same length)."""
    half = scenario.street.length_m / 2
    return override(scenario, {"street.centreline_m": [[0.0, 0.0], [half, 0.0], [half, half]]})


def bench_curved(sample_s: float = 300.0, repeats: int = 2, scenario_path: Path = SUBURBAN) -> dict:
    """Simulated seconds per CPU second of the straight and the bent street, and their ratio."""
    straight = override(load_scenario(scenario_path), {"duration_s": float(sample_s)})
    curved = bent(straight)
    model = sensor_model_for(straight)
    n = len(straight.controllers)
    print(f"== straight vs curved street, fast mode: {straight.name}, {n} controllers, {sample_s:.0f} sim s, "
          f"1 worker, best of {repeats} ==")  # fmt: skip
    cpu = {"straight": [], "curved": []}
    for _ in range(repeats):
        for name, scenario in (("straight", straight), ("curved", curved)):
            cpu[name].append(timed_comparison(scenario, 1, fidelity="fast", sensor_model=model)[1])
    rate = {name: sample_s / min(values) for name, values in cpu.items()}
    ratio = rate["straight"] / rate["curved"]
    for name in cpu:
        print(f"{name:9s} {rate[name]:6.2f} sim s per CPU-s (all {n} controllers; CPU-s of the runs: "
              f"{', '.join(f'{v:.1f}' for v in cpu[name])})")
    verdict = "met" if ratio <= TARGET_RATIO else "missed"
    print(f"the curved street costs {100 * (ratio - 1):+.1f} % per simulated second "
          f"(target <= {100 * (TARGET_RATIO - 1):.0f} %: {verdict})")
    return {"sample_s": sample_s, "cpu_s": cpu, "sim_s_per_cpu_s": rate, "cost_ratio": ratio}


if __name__ == "__main__":
    bench_curved()
