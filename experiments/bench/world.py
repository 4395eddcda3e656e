"""Traffic-recording bench: CPU seconds of ``citysim.sim.replay.record_traffic`` (the world stepped
alone at 30 Hz, no controller: the critical path of a fast-mode night) for suburban_night's
busiest hour (22:00) and its 02:00 hour, each ``sample_s`` long from an empty street
(``experiments.bench.night.night_hour``).

``bench_world()`` prints them beside the figures of the same sitting before the world's step was
compiled. The compiled kernels are loaded (from numba's on-disk cache, or compiled on a fresh
checkout) by a short warm-up record first, so the figures are the steady ones; the warm-up's own
CPU seconds are printed too (a fresh checkout's compile). CPU seconds, not wall: on a machine
shared with other jobs they are the figure to go by.

``python -m experiments.bench.world [sample_s]``.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

from citysim.config.scenario import load_scenario
from citysim.sim.replay import record_traffic
from experiments.bench.night import SUBURBAN, night_hour

#: the night's hours benched: 22:00 (the busiest) and 02:00
HOURS = {0: "22:00", 4: "02:00"}
#: record_traffic CPU-s per 1,800 simulated s before the world's step was compiled (numpy and pymunk),
#: median of 3 runs alternating with the compiled step in one sitting (fresh processes; after: 2.9 and 1.5,
#: then 4.0 and 2.1 once the moves went back to being integrated by the agents' pymunk bodies)
BEFORE_CPU_S = {0: 26.0, 4: 11.7}
BEFORE_SAMPLE_S = 1800.0
#: simulated seconds of the warm-up record (the first agents enter in its first minute)
WARM_UP_S = 60.0


def record_cpu_s(hour: int, sample_s: float) -> float:
    """CPU seconds of recording hour ``hour`` of suburban_night for ``sample_s`` simulated seconds."""
    scenario = night_hour(load_scenario(SUBURBAN), hour, sample_s)
    with tempfile.TemporaryDirectory(prefix="bench-world-") as tmp:
        t0 = time.process_time()
        record_traffic(scenario, Path(tmp) / "traffic")
        return time.process_time() - t0


def bench_world(sample_s: float = BEFORE_SAMPLE_S) -> dict[str, float]:
    """Print and return record_traffic's CPU seconds for each benched hour (and the warm-up's)."""
    if not 0 < sample_s <= 3600.0:
        raise ValueError(f"sample_s: must be in (0, 3600] s, got {sample_s}")
    out = {"warm-up": record_cpu_s(0, WARM_UP_S)}
    print(f"== traffic recording (world alone, 30 Hz), suburban_night, {sample_s:.0f} sim s per hour ==")
    print(f"warm-up ({WARM_UP_S:.0f} sim s; imports numba, loads or compiles the kernels): {out['warm-up']:.2f} CPU-s")
    for hour, clock in HOURS.items():
        cpu = out[clock] = record_cpu_s(hour, sample_s)
        before = BEFORE_CPU_S[hour] * sample_s / BEFORE_SAMPLE_S
        print(f"{clock}: {cpu:.2f} CPU-s (before: {before:.1f}, {before / cpu:.1f}x)")
    return out


if __name__ == "__main__":
    bench_world(*(float(a) for a in sys.argv[1:2]))
