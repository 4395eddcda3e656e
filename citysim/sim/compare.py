"""Run every controller of a comparison on the same night and write the run folder.

Each controller is an independent simulation of the same scenario and seed,
so they can run in parallel processes (``workers``); the traffic they see is
identical because no random stream depends on the controller. So the traffic is
simulated once, by a recorder task that runs first (``citysim.sim.replay``), and
every controller replays it instead of stepping its own pymunk world: the same
agents bit for bit, the world's cost paid once. The run folder is staged and
moved into place only when every controller finished:

    DIR/summary.json   figures per controller (``ControllerRun.summary``)
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
import signal
import time
from collections.abc import Sequence
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

from citysim.config.scenario import ControllerSpec, Scenario
from citysim.control.registry import CONTROLLERS
from citysim.metrics.crossings import OBJECTS_CSV_HEADER
from citysim.metrics.lamp_log import LAMPS_CSV_HEADER
from citysim.sim.calibration import sensor_model_for
from citysim.sim.loop import check_controllers, check_fidelity, controller_spec
from citysim.sim.progress import SimulatedTimeBar
from citysim.sim.replay import record_traffic
from citysim.sim.together import part_path, run_together
from citysim.sim.workers import WorkerLost, describe_exit, exit_codes, spawn_pool, worker_processes
from citysim.world.approaches import approaches
from citysim.world.coverage import camera_coverage
from citysim.world.street import build_street
from detector.outdir import raise_if_terminated, staged_folder

#: Every comparison holds these (savings are against always-on, and against the oracle's bound,
#: measured on the same night), first, in this order.
REFERENCE_CONTROLLERS = ("always_on", "oracle")


def controller_names(text: str | None) -> list[str] | None:
    """The names of a comma-separated --controllers value (None when not given: the scenario's list)."""
    return [n.strip() for n in text.split(",") if n.strip()] if text else None


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


#: The oracle's savings against always-on (a share) below which it saves nothing to take a share of:
#: ``savings_vs_oracle`` and the gap split are None. Reasoning: docs/design/frontier-and-hold.md.
ORACLE_SAVES_NOTHING_BELOW = 0.01


def oracle_bound(results: dict[str, dict]) -> float | None:
    """The oracle's savings against always-on in ``results`` (label -> figures with ``controller``
    and ``savings_vs_always_on``, a share), the bound every other saving is a share of; None without
    an oracle or when it saves less than ``ORACLE_SAVES_NOTHING_BELOW``."""
    oracle = next((r for r in results.values() if r.get("controller") == "oracle"), None)
    saving = None if oracle is None else oracle.get("savings_vs_always_on")
    return saving if saving is not None and saving >= ORACLE_SAVES_NOTHING_BELOW else None


def with_savings_vs_oracle(results: dict[str, dict]) -> dict[str, dict]:
    """Each controller's savings as a share of the oracle's (1: as much as the bound; None without
    an oracle or when the oracle saves nothing, ``oracle_bound``), placed after
    ``savings_vs_always_on``; with an ``oracle_seen`` in the comparison also the split of the gap
    (``gap_split``)."""
    bound = oracle_bound(results)
    seen = next((r for r in results.values() if r["controller"] == "oracle_seen"), None)
    out = {}
    for label, result in results.items():
        share = result["savings_vs_always_on"] / bound if bound else None
        ordered = {}
        for key, value in result.items():
            ordered[key] = value
            if key == "savings_vs_always_on":
                ordered["savings_vs_oracle"] = share
                if seen is not None:
                    ordered.update(gap_split(result, bound, seen))
        out[label] = ordered
    return out


def gap_split(result: dict, oracle_savings: float | None, seen: dict) -> dict:
    """A controller's gap to the oracle split by ``seen``, oracle_seen's result (the oracle knowing
    only what a perfect detector in the cameras sees), on both of the planner's axes.

    Savings, in shares of the oracle's savings (None where ``oracle_bound`` is None): ``gap_unseen`` =
    oracle minus oracle_seen (the same for every controller; below 0 where oracle_seen saves more
    by not lighting for road users no camera sees) and ``gap_unused`` = oracle_seen minus the
    controller (energy beyond what a perfect use of its cameras would spend). Lit on entry:
    ``dark_unseen`` = 1 minus oracle_seen's rate (entries no camera could announce in time) and
    ``dark_unused`` = oracle_seen's rate minus the controller's (entries its cameras could have
    announced and it left dark; below 0 where it lights blind entries by other means)."""
    seen_savings, seen_lit = seen["savings_vs_always_on"], seen.get("lit_on_entry_rate")
    lit = result.get("lit_on_entry_rate")
    out = {"gap_unseen": None, "gap_unused": None}
    if oracle_savings:
        out = {"gap_unseen": (oracle_savings - seen_savings) / oracle_savings,
               "gap_unused": (seen_savings - result["savings_vs_always_on"]) / oracle_savings}
    out["dark_unseen"] = None if seen_lit is None else 1.0 - seen_lit
    out["dark_unused"] = None if seen_lit is None or lit is None else seen_lit - lit
    return out


#: A worker sends its progress at most this often, wall s: every put is a round trip to the
#: manager process, and a fast night's six workers sent one per 5 sim s (35k for 28,800 s)
PROGRESS_EVERY_S = 0.25


class _Batched:
    """Progress of a worker process, sent to the parent's queue in batches of >= 5 sim s and at
    most every ``PROGRESS_EVERY_S`` of wall time."""

    def __init__(self, progress_queue):
        self.queue, self.pending_s, self.sent_at = progress_queue, 0.0, time.monotonic()

    def __call__(self, dt_s: float) -> None:
        self.pending_s += dt_s
        if self.queue is not None and self.pending_s >= 5.0 and time.monotonic() - self.sent_at >= PROGRESS_EVERY_S:
            self.flush()

    def flush(self) -> None:
        if self.queue is not None and self.pending_s > 0:
            self.queue.put(self.pending_s)
            self.sent_at = time.monotonic()
        self.pending_s = 0.0


def _worker(args):
    """One task of a pool: the traffic recorder (no specs), or a group of controllers
    (``run_together``, one controller alone the usual group); returns the summaries by display name.
    Tells the parent first which process runs it (``("started", task, pid)``)."""
    task, scenario, specs, part_dir, progress_queue, traffic, fidelity, sensor_model = args
    progress_queue.put(("started", task, os.getpid()))
    report = _Batched(progress_queue)
    traffic = None if traffic is None else Path(traffic)
    if specs:
        summaries = run_together(scenario, specs, Path(part_dir), traffic=traffic, fidelity=fidelity,
                                 sensor_model=sensor_model, on_progress=report)[0]  # fmt: skip
    else:
        record_traffic(scenario, traffic, on_progress=report)
        summaries = {}
    report.flush()
    return summaries


def _run_here(scenario, groups, parts, traffic, fidelity, sensor_model, bar) -> dict[str, dict]:
    """The comparison's tasks one after the other in this process."""
    if traffic is not None:
        record_traffic(scenario, traffic, on_progress=bar.update)
    results: dict[str, dict] = {}
    for group in groups:
        results.update(run_together(scenario, group, parts, traffic=traffic, fidelity=fidelity,
                                    sensor_model=sensor_model, on_progress=bar.update)[0])  # fmt: skip
    return results


def _run_in_pool(scenario, groups, parts, traffic, fidelity, sensor_model, bar, workers: int) -> dict[str, dict]:
    """The comparison's tasks on ``workers`` processes, the traffic recorder first: the controllers
    replay its chunks as it writes them. A worker that dies mid-task (SIGKILL, out of memory)
    stops the comparison with ``WorkerLost`` naming its controllers."""
    results: dict[str, dict] = {}
    traffic_arg = None if traffic is None else str(traffic)
    tasks = ([] if traffic is None else [[]]) + list(groups)  # [] is the recorder
    started: dict[int, int] = {}  # task -> pid of the worker running it
    processes: dict[int, object] = {}  # pid -> Process, kept past the pool's own table
    with mp.Manager() as manager:
        q = manager.Queue()
        with spawn_pool(workers) as pool:
            pending = {pool.submit(_worker, (i, scenario, group, str(parts), q, traffic_arg, fidelity, sensor_model)): i
                       for i, group in enumerate(tasks)}  # fmt: skip
            while pending:
                processes.update(worker_processes(pool))
                _drain(q, bar, started, timeout_s=0.2)
                for f in [f for f in pending if f.done()]:
                    task = pending.pop(f)
                    try:
                        results.update(f.result())
                    except BrokenProcessPool:
                        raise_if_terminated()  # the workers went because the user stopped the run
                        exits = exit_codes({**processes, **worker_processes(pool)})
                        _drain(q, bar, started, timeout_s=None)  # "started" notes still on their way
                        raise WorkerLost(_lost_message(tasks, started, exits, task)) from None
            _drain(q, bar, started, timeout_s=None)
    return results


def _drain(q, bar, started: dict[int, int], timeout_s: float | None) -> None:
    """Take the progress queue's messages: sim seconds for the bar, ``("started", task, pid)``
    notes; wait up to ``timeout_s`` for the first (None: take only what is there)."""
    while True:
        try:
            item = q.get(timeout=timeout_s) if timeout_s is not None else q.get_nowait()
        except queue.Empty:
            return
        timeout_s = None
        if isinstance(item, tuple):
            started[item[1]] = item[2]
        else:
            bar.update(item)


def _lost_message(tasks, started: dict[int, int], exits: dict[int, int | None], task: int) -> str:
    """One line: which task's worker died and how; ``task`` the one whose future broke first."""
    # SIGTERM is the pool's own clean-up of the other workers once one died
    killed = [pid for pid, code in exits.items() if code is not None and code < 0 and code != -signal.SIGTERM]
    pid = killed[0] if killed else started.get(task)
    running = [t for t, p in started.items() if p == pid]
    if pid is not None and not running:
        return (f"a worker process (pid {pid}) ended before it took a task ({describe_exit(exits.get(pid))}); "
                "nothing was written; run the same command again")
    task = running[-1] if running else task
    names = ", ".join(s.display_name for s in tasks[task]) or "the traffic recorder"
    return (f"the worker process running {'controller ' if tasks[task] else ''}{names}"
            f"{f' (pid {pid})' if pid is not None else ''} ended mid-run ({describe_exit(exits.get(pid))}); "
            "nothing was written; run the same command again")


def run_groups(specs: Sequence[ControllerSpec], fidelity: str, workers: int, share_frames: bool) -> list[list[ControllerSpec]]:
    """The comparison's tasks: each a list of controllers run together. At full fidelity with
    ``share_frames``, the camera controllers are dealt into one group per worker, run in step,
    sharing the frames they render alike (``citysim.sim.together``); every other controller runs
    alone. Camera controllers come first: the cheap ones fill the gaps at the end."""
    cameras = [s for s in specs if CONTROLLERS[s.name].uses_camera]
    others = [[s] for s in specs if not CONTROLLERS[s.name].uses_camera]
    if fidelity != "full" or not share_frames or len(cameras) < 2:
        return [[s] for s in cameras] + others
    n_groups = max(1, min(workers, len(cameras)))
    return [cameras[g::n_groups] for g in range(n_groups)] + others


def run_comparison(
    scenario: Scenario,
    controllers: Sequence[str] | None = None,
    *,
    progress: bool = False,
    out_dir: Path | None = None,
    workers: int = 1,
    scenario_file: str | None = None,
    replay_traffic: bool = True,
    fidelity: str = "full",
    sensor_model=None,
    cache_dir: Path | None = None,
    share_frames: bool = False,
) -> dict:
    """Run the controllers on the same traffic; return the summary.json dict and, with ``out_dir``,
    write the run folder (summary.json, objects.csv, lamps.csv; ``citysim.report`` plots them).

    Parameters
    ----------
    scenario : citysim.config.scenario.Scenario
        The night to run; ``scenario.duration_s`` (s) simulated per controller.
    controllers : sequence of str, optional
        Registered controller names (``citysim.control.registry``); None: the scenario's list.
        always_on and the oracle are always added (the savings and the bound).
    progress : bool
        Show a progress bar of simulated seconds, with rate and time left.
    out_dir : pathlib.Path, optional
        The run folder to write (staged: nothing half-written); None writes nothing.
    workers : int
        Processes to run the controllers in (at most one per controller).
    scenario_file : str, optional
        The scenario's file name, recorded in summary.json.
    replay_traffic : bool
        Simulate the traffic once and replay it to every controller (the default); False steps a
        world per controller (the same results, bit for bit, at a higher cost).
    fidelity : {"full", "fast"}
        "fast": cameras judged by the scenario's sensor model (``sensor_model``, else the one cached
        in ``cache_dir``, calibrated first if there is none; ``citysim.sim.calibration``).
    sensor_model, cache_dir : citysim.fast.model.SensorModel, pathlib.Path, optional
        The model fast mode draws from; the folder where calibrated models are cached.
    share_frames : bool
        At full fidelity, run the camera controllers in step, a group per worker, rendering a
        frame once for all of a group whose lamps stand alike (the same results, bit for bit).
        Off by default: on suburban_night it saves renders but not time.

    Returns
    -------
    dict
        summary.json: scenario, seed, duration_s (s), fidelity, lamps, camera coverage,
        approaches, and per controller label its figures (energy_kwh, savings_vs_always_on and
        savings_vs_oracle as shares, lit_on_entry_rate 0..1, lags and dark seconds in s, ...).
    """
    specs = resolve_controllers(scenario, controllers)
    check_fidelity(fidelity)
    if fidelity == "fast" and sensor_model is None and needs_sensor_model(specs):
        sensor_model = sensor_model_for(scenario, cache_dir, progress=progress)
    workers = max(1, min(workers, len(specs)))
    summary = {"scenario": scenario.name, "scenario_file": scenario_file, "seed": scenario.seed,
               "duration_s": scenario.duration_s, "fidelity": fidelity, "lamps": None,
               "coverage": camera_coverage(build_street(scenario)).as_dict(),
               "approaches": approaches(scenario).as_dict(), "controllers": {}}
    with staged_folder(out_dir) if out_dir is not None else _scratch() as stage:
        parts = stage / ".parts"
        traffic = stage / ".traffic" if replay_traffic else None
        total_s = scenario.duration_s * (len(specs) + (traffic is not None))
        groups = run_groups(specs, fidelity, workers, share_frames)
        tasks = (scenario, groups, parts, traffic, fidelity, sensor_model)
        with SimulatedTimeBar(total_s, f"{scenario.name}: {len(specs)} controllers", disable=not progress) as bar:
            results = _run_here(*tasks, bar) if workers == 1 else _run_in_pool(*tasks, bar, workers)
        results = with_savings_vs_oracle({spec.display_name: results[spec.display_name] for spec in specs})
        summary["controllers"] = results
        summary["lamps"] = scenario.lamps.count or len(scenario.lamps.positions_x_m)
        _merge_parts(parts, [s.display_name for s in specs], stage)
        shutil.rmtree(parts, ignore_errors=True)
        if traffic is not None:
            shutil.rmtree(traffic, ignore_errors=True)
        (stage / "summary.json").write_text(json.dumps(summary, indent=2))
    return summary


def _merge_parts(parts: Path, labels: list[str], stage: Path) -> None:
    for kind, header in (("lamps", LAMPS_CSV_HEADER), ("objects", OBJECTS_CSV_HEADER)):
        with open(stage / f"{kind}.csv", "w", newline="") as out:
            csv.writer(out).writerow(header)
            for label in labels:
                part = part_path(parts, label, kind)
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
