"""Whole-night bench: every controller of suburban_night, full fidelity and fast mode, on 2 workers.

``bench_night(duration_s)`` times full fidelity over the night's first ``duration_s`` s;
``bench_night_fast(sample_s)`` and ``bench_night_full_hours(sample_s)`` sample each hour of the
night and sum; ``bench_night_fast_whole()`` runs the whole night in fast mode. Wall and CPU
seconds (this process and every worker).

``python -m experiments.bench --night`` runs the whole night at full fidelity (long); ``make bench`` samples.

Design: docs/design/modules.md (The whole-night bench)
"""

from __future__ import annotations

import resource
import tempfile
import time
from pathlib import Path

from citysim.config.scenario import Scenario, load_scenario, override
from citysim.sim.compare import run_comparison
from citysim.year.factors import target_classes

REPO = Path(__file__).resolve().parents[2]
SUBURBAN = REPO / "scenarios" / "suburban_night.yaml"
WHOLE_NIGHT_S = 28_800.0
#: every controller of suburban_night, a whole night on 2 cores, before this bench existed
BEFORE_WHOLE_NIGHT_WALL_S = 1.8 * 3600.0
#: fast mode before: every controller, per 600 simulated seconds
BEFORE_FAST_CPU_S, BEFORE_FAST_SIM_S = 249.0, 600.0
#: the run length ``make bench`` samples at full fidelity (the first 10 minutes: the busiest of the night)
SAMPLE_S = 600.0
#: simulated seconds of each hour fast mode samples
FAST_SAMPLE_S = 600.0
#: simulated seconds of each hour the full-fidelity night samples (``make bench-night`` runs it whole)
FULL_HOUR_SAMPLE_S = 300.0


def cpu_s() -> float:
    """CPU seconds of this process and of its reaped child processes so far."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def timed_comparison(scenario: Scenario, workers: int, **kwargs) -> tuple[float, float]:
    """(wall s, CPU s) of one comparison of every controller, its run folder thrown away."""
    with tempfile.TemporaryDirectory(prefix="bench-night-") as tmp:
        c0, t0 = cpu_s(), time.perf_counter()
        run_comparison(scenario, out_dir=Path(tmp) / "run", workers=workers, **kwargs)
        return time.perf_counter() - t0, cpu_s() - c0


#: what each fidelity's whole night of every controller took before, and its target
BEFORE_WHOLE_NIGHT = {
    "full": f"before: {BEFORE_WHOLE_NIGHT_WALL_S / 3600:.1f} h wall; target <= 15 min",
    "fast": ("before: 6.8 min wall, 795 CPU-s (one run, before the replayed steps' metrics, oracle, PIR and fast "
             "sensing were batched per chunk; 15.1 min, 1,054 CPU-s before the world's step was compiled); "
             "target <= 30 s"),
}


def bench_night(duration_s: float = SAMPLE_S, workers: int = 2, scenario_path: Path = SUBURBAN,
                fidelity: str = "full") -> dict:  # fmt: skip
    """Wall and CPU seconds of every controller over ``duration_s`` in ``fidelity`` on ``workers``
    processes, and the whole night's (measured, or scaled from the sample)."""
    if not 0 < duration_s <= WHOLE_NIGHT_S:
        raise ValueError(f"duration_s: must be in (0, {WHOLE_NIGHT_S:.0f}] s, got {duration_s}")
    scenario = override(load_scenario(scenario_path), {"duration_s": float(duration_s)})
    n = len(scenario.controllers)
    mode = "full fidelity" if fidelity == "full" else "fast mode"
    print(f"== whole night, {mode}: {scenario.name}, {n} controllers, {duration_s:.0f} sim s, {workers} workers ==")
    wall_s, cpu = timed_comparison(scenario, workers, fidelity=fidelity, progress=fidelity == "full")
    scale = WHOLE_NIGHT_S / duration_s
    how = "measured" if duration_s >= WHOLE_NIGHT_S else f"scaled from the first {duration_s:.0f} s, an upper bound"
    print(f"{n} controllers x {duration_s:.0f} sim s: {wall_s:.0f} s wall, {cpu:.0f} CPU-s "
          f"({duration_s * n / wall_s:.1f} sim s per wall s, all controllers together)")
    print(f"whole night, every controller, {mode}, {workers} cores: {wall_s * scale / 60:.1f} min wall, "
          f"{cpu * scale:.0f} CPU-s, {cpu * scale / 3600:.2f} CPU-h ({how}); {BEFORE_WHOLE_NIGHT[fidelity]}")
    return {"fidelity": fidelity, "duration_s": duration_s, "wall_s": wall_s, "cpu_s": cpu,
            "whole_night_wall_s": wall_s * scale, "whole_night_cpu_s": cpu * scale}  # fmt: skip


def night_hour(scenario: Scenario, hour: int, sample_s: float) -> Scenario:
    """Hour ``hour`` of the scenario's night as a run of its own, ``sample_s`` long (see the module doc)."""
    updates: dict = {"duration_s": float(sample_s), "start_hour": (scenario.start_hour + hour) % 24}
    if hour:
        updates["traffic.scripted"] = []
        for name, spec in target_classes(scenario).items():
            profile = list(spec.hourly_profile)
            if profile:
                updates[f"traffic.classes.{name}.hourly_profile"] = profile[min(hour, len(profile) - 1):]
    return override(scenario, updates)


def bench_night_fast(sample_s: float = FAST_SAMPLE_S, workers: int = 2, scenario_path: Path = SUBURBAN) -> dict:
    """Fast mode, every controller, one ``sample_s`` sample per hour of the night, scaled to the night."""
    before = BEFORE_FAST_CPU_S * WHOLE_NIGHT_S / BEFORE_FAST_SIM_S
    return bench_night_hours(
        "fast", sample_s, workers, scenario_path,
        before=f"before: {BEFORE_FAST_CPU_S:.0f} CPU-s per {BEFORE_FAST_SIM_S:.0f} sim s, {before:,.0f} CPU-s "
        "scaled to the night; target <= 30 s",
    )  # fmt: skip


def bench_night_fast_whole(workers: int = 2, scenario_path: Path = SUBURBAN) -> dict:
    """Fast mode, every controller, the whole night (22:00-06:00) as one run, measured (no sampling,
    so nothing is scaled: the pool's start-up and the traffic recorder count once, as in a user's
    ``citysim run --fidelity fast --duration 28800``)."""
    return bench_night(WHOLE_NIGHT_S, workers, scenario_path, fidelity="fast")


def bench_night_full_hours(sample_s: float = FULL_HOUR_SAMPLE_S, workers: int = 2, scenario_path: Path = SUBURBAN) -> dict:
    """Full fidelity, every controller, one ``sample_s`` sample per hour of the night, scaled to the
    night: each sample starts from an empty street, so slow walkers (a 400 m street takes them
    about 5 minutes) are under-counted and the figure is a lower estimate, where ``bench_night``'s
    first minutes scaled to the night are an upper one."""
    out = bench_night_hours(
        "full", sample_s, workers, scenario_path,
        before=f"before: about {BEFORE_WHOLE_NIGHT_WALL_S / 3600:.1f} h wall; target <= 15 min",
    )  # fmt: skip
    busiest = max(out["hours"], key=lambda h: h["cpu_s"])
    hours = len(out["hours"])
    print(f"upper bound, every hour as busy as the busiest sample (hour {busiest['hour']}): "
          f"{busiest['wall_s'] * hours / 60:.1f} min wall, {busiest['cpu_s'] * hours:.0f} CPU-s")
    return out


def bench_night_hours(fidelity: str, sample_s: float, workers: int, scenario_path: Path, before: str) -> dict:
    """Every controller in ``fidelity``, one ``sample_s`` sample per hour of the night (``night_hour``),
    each scaled to its hour and the hours summed; prints each hour and the night beside ``before``."""
    if not 0 < sample_s <= 3600:
        raise ValueError(f"sample_s: must be in (0, 3600] s, got {sample_s}")
    base = load_scenario(scenario_path)
    hours = int(WHOLE_NIGHT_S // 3600)
    n = len(base.controllers)
    mode = "fast mode" if fidelity == "fast" else "full fidelity"
    print(f"== whole night, {mode}: {base.name}, {n} controllers, a {sample_s:.0f} s sample of each of its "
          f"{hours} hours, {workers} workers ==")
    wall = cpu = 0.0
    per_hour = []
    for hour in range(hours):
        w, c = timed_comparison(night_hour(base, hour, sample_s), workers, fidelity=fidelity, progress=False)
        scale = 3600.0 / sample_s
        per_hour.append({"hour": hour, "wall_s": w * scale, "cpu_s": c * scale})
        wall, cpu = wall + w * scale, cpu + c * scale
        print(f"  hour {hour} ({(base.start_hour + hour) % 24:02.0f}:00): {w:.0f} s wall, {c:.0f} CPU-s "
              f"per {sample_s:.0f} sim s -> {c * scale:.0f} CPU-s per hour", flush=True)
    print(f"whole night, every controller, {mode}, {workers} cores: {wall / 60:.1f} min wall, {cpu:.0f} CPU-s "
          f"(scaled from the hourly samples); {before}")
    return {"fidelity": fidelity, "sample_s": sample_s, "hours": per_hour, "whole_night_wall_s": wall,
            "whole_night_cpu_s": cpu}  # fmt: skip


#: simulated seconds of each hour the shared-frames A/B runs, and the hours it samples (22:00, 23:00, 02:00)
SHARED_SAMPLE_S, SHARED_HOURS = 300.0, (0, 1, 4)


def bench_shared_frames(sample_s: float = SHARED_SAMPLE_S, workers: int = 2, scenario_path: Path = SUBURBAN) -> dict:
    """Full fidelity, every controller, with and without the camera controllers sharing their frames
    (``run_comparison(share_frames=...)``), alternating, at the busy 22:00, at 23:00 and at the quiet
    02:00: the floor (each controller alone, the default) is measured in the same run, on the same
    traffic. Sharing is off by default because this comparison found no time saved."""
    base = load_scenario(scenario_path)
    print(f"== shared frames, full fidelity: {base.name}, every controller, {sample_s:.0f} sim s, {workers} workers, "
          f"each controller alone (before) against the camera controllers in step (now) ==")
    out = []
    for hour in SHARED_HOURS:
        scenario = night_hour(base, hour, sample_s)
        alone = timed_comparison(scenario, workers, share_frames=False, progress=False)
        shared = timed_comparison(scenario, workers, share_frames=True, progress=False)
        print(f"  {(base.start_hour + hour) % 24:02.0f}:00: alone {alone[0]:.0f} s wall, {alone[1]:.0f} CPU-s; "
              f"in step {shared[0]:.0f} s wall, {shared[1]:.0f} CPU-s (in step: {100 * (shared[1] / alone[1] - 1):+.1f} % CPU)",
              flush=True)  # fmt: skip
        out.append({"hour": hour, "alone_wall_s": alone[0], "alone_cpu_s": alone[1],
                    "shared_wall_s": shared[0], "shared_cpu_s": shared[1]})  # fmt: skip
    return {"sample_s": sample_s, "hours": out}
