"""Parameter sweeps on Dask: one task per sweep point, results written as points finish.

``run_sweep(sweep_file, out_dir)`` expands a sweep file (``citysim.sweep.spec``)
into points (axes x seeds), skips the points DIR/results.csv already holds,
and runs the rest on Dask distributed: a ``LocalCluster`` of single-threaded
worker processes by default, or the cluster behind ``scheduler`` (an address
such as ``tcp://10.0.0.5:8786``). Each task runs ``citysim.sim.compare.run_comparison`` for
one point (every controller on the same traffic) and returns its rows; the
client process alone appends them to results.csv the moment the task finishes,
so an interrupted sweep resumes where it stopped. A point whose scenario is
invalid, or whose run raises, gets status ``failed`` with the error message
and the sweep goes on.

The output folder::

    DIR/sweep.json                 the resolved sweep (axes, seeds, controllers, base scenario)
    DIR/results.csv                one row per point and controller (see sweep_results)
    DIR/points/<point_id>/         summary.json and objects.csv of each point (save_objects)

Rows depend only on the point (axis values + seed), never on the worker that
ran it: the simulation draws all randomness from the point's seed.
"""

from __future__ import annotations

import json
import logging
import os
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from citysim.config.scenario import Scenario, ScenarioError
from citysim.fast import FIDELITIES
from citysim.sweep.fidelity import check_points, check_report, sensor_models, write_check
from citysim.sweep.results import ResultsFile, flatten_summary
from citysim.sweep.spec import ResolvedSweep, SweepError, SweepPoint, load_sweep

__all__ = ["PointResult", "SweepError", "kept_points", "load_sweep", "run_point", "run_sweep"]

#: How long to wait for a scheduler given by address before giving up (s).
SCHEDULER_TIMEOUT_S = 20.0
IDENTITY_COLUMNS = ("point_id", "seed", "controller", "status", "error", "finished_at", "wall_s")


@dataclass(frozen=True)
class PointResult:
    """What a task sends back to the client: the point's rows and its run files' text."""

    point_id: str
    rows: list[dict[str, Any]]
    files: dict[str, str] = field(default_factory=dict)


def _identity(point: SweepPoint, controller: str) -> dict[str, Any]:
    return {"point_id": point.point_id, **point.axes, "seed": point.seed, "controller": controller}


def failed_rows(point: SweepPoint, controllers: Sequence[str], error: str) -> list[dict[str, Any]]:
    """One ``failed`` row per controller; the error on one line."""
    message = " ".join(error.split())
    stamp = datetime.now(UTC).isoformat(timespec="milliseconds")
    return [
        {**_identity(point, c), "status": "failed", "error": message, "finished_at": stamp}
        for c in controllers
    ]


def run_point(
    point: SweepPoint, scenario: Scenario, controllers: Sequence[str], save_objects: bool,
    fidelity: str = "full", sensor_model=None,
) -> PointResult:
    """The Dask task: every controller of ``scenario`` on one point. Never raises: failures are rows."""
    import threading

    from tqdm import tqdm

    from citysim.sim.compare import run_comparison

    # no bar is shown here; tqdm's default lock, a multiprocessing semaphore, would be reported
    # leaked by the resource tracker when the cluster's processes are ended by a stopped sweep
    tqdm.set_lock(threading.RLock())
    t0 = time.perf_counter()
    files: dict[str, str] = {}
    try:
        with tempfile.TemporaryDirectory(prefix="citysim-point-") as tmp:
            out_dir = Path(tmp) / "run" if save_objects else None
            summary = run_comparison(scenario, progress=False, out_dir=out_dir, workers=1, fidelity=fidelity,
                                     sensor_model=sensor_model)  # fmt: skip
            if out_dir is not None and (out_dir / "objects.csv").exists():
                files["objects.csv"] = (out_dir / "objects.csv").read_text()
    except Exception as exc:  # a run that raises is a failed point, not a failed sweep
        return PointResult(
            point.point_id, failed_rows(point, controllers, f"{type(exc).__name__}: {exc}")
        )
    files["summary.json"] = json.dumps(summary, indent=2, sort_keys=True)
    wall_s = time.perf_counter() - t0
    stamp = datetime.now(UTC).isoformat(timespec="milliseconds")
    reserved = set(IDENTITY_COLUMNS) | set(point.axes) | {"n_lamps", "duration_s", "camera_coverage"}
    rows = []
    figures_by_controller = summary.get("controllers", {})
    for c in controllers:
        figures = figures_by_controller.get(c)
        if figures is None:
            rows.extend(failed_rows(point, [c], f"run_comparison returned no figures for {c!r}"))
            continue
        rows.append(
            {
                **_identity(point, c),
                "status": "ok",
                "error": "",
                "finished_at": stamp,
                "wall_s": round(wall_s, 3),
                "n_lamps": summary.get("lamps"),
                "duration_s": summary.get("duration_s"),
                "camera_coverage": summary.get("coverage", {}).get("street_seen"),
                **flatten_summary(figures, reserved),
            }
        )
    return PointResult(point.point_id, rows, files)


@dataclass
class _Client:
    """A Dask client and, for the default local cluster, the cluster it owns."""

    client: Any
    cluster: Any = None

    def close(self) -> None:
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def connect(scheduler: str | None, workers: int | None) -> _Client:
    """Client(scheduler) for a real cluster, else a LocalCluster of ``workers`` 1-thread processes."""
    from distributed import Client

    if scheduler is not None:
        try:
            return _Client(Client(scheduler, timeout=f"{SCHEDULER_TIMEOUT_S}s"))
        except (OSError, TimeoutError) as exc:
            raise SweepError(f"scheduler {scheduler!r}: cannot connect ({exc})") from None
    from citysim.sim.workers import sigint_ignored_by_children

    n = workers if workers is not None else max(1, os.cpu_count() or 1)
    # Ctrl-C reaches the whole terminal group: the cluster's processes ignore it (else each prints
    # a traceback), so only this process stops, and closes the cluster
    with sigint_ignored_by_children():
        return _local(n)


def _local(n: int) -> _Client:
    """A LocalCluster of ``n`` single-threaded worker processes on loopback, and its client."""
    from distributed import Client, LocalCluster

    cluster = LocalCluster(
        n_workers=n,
        threads_per_worker=1,
        processes=True,
        # the scheduler serves HTTP (health checks) even without a dashboard: a free port, not 8787
        dashboard_address="127.0.0.1:0",
        silence_logs=logging.ERROR,
        host="127.0.0.1",
    )
    return _Client(Client(cluster), cluster)


def _save_files(out_dir: Path, result: PointResult) -> None:
    if not result.files:
        return
    folder = out_dir / "points" / result.point_id
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in result.files.items():
        (folder / name).write_text(text)


def _check_same_sweep(out_dir: Path, resolved: ResolvedSweep, fidelity: str) -> None:
    """Refuse to mix rows of a different base scenario, duration or controller set into DIR."""
    path = out_dir / "sweep.json"
    if not path.exists():
        return
    try:
        old = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError):
        return  # an unreadable sweep.json is rewritten below
    if old.get("fingerprint") not in (None, resolved.fingerprint()):
        raise SweepError(
            f"{out_dir}: holds results of a different sweep (base scenario, duration_s, set or "
            f"controllers changed since {old.get('sweep_file')}); use a new output folder"
        )
    if old.get("fidelity", "full") != fidelity and (out_dir / "results.csv").exists():
        raise SweepError(f"fidelity: {out_dir} holds {old.get('fidelity', 'full')} results; resume it with "
                         f"--fidelity {old.get('fidelity', 'full')} or use a new output folder")

def run_sweep(
    sweep_file: str | Path,
    out_dir: str | Path,
    scheduler: str | None = None,
    workers: int | None = None,
    progress: bool = True,
    *,
    retry_failed: bool = False,
    max_points: int | None = None,
    fidelity: str = "fast",
    full_checks: int = 2,
    cache_dir: Path | None = None,
) -> dict[str, Any]:
    """Run (or resume) a sweep into ``out_dir``; returns counts and paths.

    ``scheduler``: a Dask scheduler address; None starts a local cluster of
    ``workers`` (default: one per CPU) single-threaded processes.
    ``retry_failed`` runs points recorded as failed again; ``max_points`` runs at
    most that many of the unfinished points (a partial sweep, resumed later).
    ``fidelity``: "fast" (default; camera controllers judged by the calibrated sensor model, see
    ``citysim.sweep.fidelity``) or "full"; in fast mode ``full_checks`` of the points run are
    re-run in full fidelity and compared (DIR/fidelity_check.json, counts["check"]).
    Returns ``{"points", "skipped", "ran", "ok", "failed", "results", "sweep_json"}`` (+ "check").
    Raises SweepError (a ValueError) for a bad sweep file, folder or scheduler.
    """
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise SweepError(f"workers: a whole number >= 1, got {workers!r}")
    if fidelity not in FIDELITIES:
        raise SweepError(f"fidelity: unknown {fidelity!r}; valid: {', '.join(FIDELITIES)}")
    resolved = load_sweep(sweep_file)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    _check_same_sweep(out_dir, resolved, fidelity)
    (out_dir / "sweep.json").write_text(json.dumps({**resolved.to_json(), "fidelity": fidelity}, indent=2) + "\n")

    controllers = resolved.controller_labels
    results = ResultsFile(out_dir / "results.csv", resolved.axis_names)
    points = resolved.points()
    wanted = {p.point_id for p in points}
    finished = {k: v for k, v in results.finished_points(controllers).items() if k in wanted}
    stale = {r["point_id"] for r in results.rows if r["point_id"] in wanted} - set(finished)
    if retry_failed:
        stale |= {k for k, v in finished.items() if v == "failed"}
        finished = {k: v for k, v in finished.items() if v == "ok"}
    results.drop_points(stale)
    todo = [p for p in points if p.point_id not in finished]
    if max_points is not None:
        todo = todo[: max(0, max_points)]
    counts = {"points": len(points), "skipped": len(finished), "ran": 0, "ok": 0, "failed": 0}

    def record(result: PointResult) -> None:
        results.append(result.rows)
        _save_files(out_dir, result)
        counts["ran"] += 1
        status = "ok" if all(r["status"] == "ok" for r in result.rows) else "failed"
        counts[status] += 1

    runnable: list[tuple[SweepPoint, Scenario]] = []
    for point in todo:
        try:
            runnable.append((point, resolved.scenario_for(point)))
        except ScenarioError as exc:
            record(PointResult(point.point_id, failed_rows(point, controllers, str(exc))))

    if runnable:
        tasks = _tasks(runnable, fidelity, full_checks, cache_dir, progress)
        checks = _run_on_dask(tasks, controllers, resolved.spec.save_objects, scheduler, workers,
                              progress, record)  # fmt: skip
        if checks:
            report = check_report(checks)
            counts["check"] = {"points": len(checks), "cells": report["cells"], "cells_pass": report["cells_pass"],
                               "file": write_check(out_dir, report)}  # fmt: skip
    return {**counts, "results": out_dir / "results.csv", "sweep_json": out_dir / "sweep.json"}


def kept_points(sweep_file: str | Path, out_dir: str | Path) -> tuple[int, int]:
    """(points of the sweep finished in ``out_dir``, points of the sweep): what a resumed run skips."""
    resolved = load_sweep(sweep_file)
    points = resolved.points()
    path = Path(out_dir) / "results.csv"
    if not path.exists():
        return 0, len(points)
    finished = ResultsFile(path, resolved.axis_names).finished_points(resolved.controller_labels)
    return len({p.point_id for p in points} & set(finished)), len(points)


def _tasks(runnable, fidelity: str, full_checks: int, cache_dir, progress: bool) -> list[tuple]:
    """(point, scenario, fidelity, sensor model, is_check) for every run to send to Dask."""
    if fidelity == "full":
        return [(point, scenario, "full", None, False) for point, scenario in runnable]
    models = sensor_models([scenario for _, scenario in runnable], cache_dir, progress)
    tasks = [(point, scenario, "fast", model, False) for (point, scenario), model in zip(runnable, models, strict=True)]
    # a point without camera controllers runs alike in both fidelities: nothing to check
    camera = [i for i, model in enumerate(models) if model is not None]
    checked = [camera[i] for i in check_points(len(camera), full_checks)]
    return tasks + [(runnable[i][0], runnable[i][1], "full", None, True) for i in checked]


def _run_on_dask(tasks, controllers, save_objects, scheduler, workers, progress, record) -> list[tuple]:
    """Run the tasks; record each point's rows; the (point_id, full, fast) summaries of the checks."""
    from distributed import as_completed
    from tqdm import tqdm

    handle = connect(scheduler, workers)
    summaries: dict[tuple[str, bool], dict] = {}
    try:
        tasks_by_key = {}
        futures = []
        for task in tasks:
            point, scenario, fidelity, model, is_check = task
            fut = handle.client.submit(
                run_point, point, scenario, list(controllers), save_objects and not is_check, fidelity, model,
                key=f"citysim-point-{point.point_id}-{fidelity}-{time.time_ns()}", pure=False,
            )  # fmt: skip
            tasks_by_key[fut.key] = task
            futures.append(fut)
        bar = tqdm(total=len(futures), desc="sweep points", unit="point", disable=not progress)
        with bar:
            for fut in as_completed(futures):
                point, _, _, _, is_check = tasks_by_key[fut.key]
                try:
                    result = fut.result()
                except Exception as exc:  # the worker died or the task could not be sent
                    result = PointResult(
                        point.point_id,
                        failed_rows(point, controllers, f"{type(exc).__name__}: {exc}"),
                    )
                if "summary.json" in result.files:
                    summaries[(point.point_id, is_check)] = json.loads(result.files["summary.json"])
                if not is_check:
                    record(result)
                fut.release()
                bar.update(1)
    finally:
        handle.close()
    return [(pid, full, summaries[(pid, False)]) for (pid, is_check), full in summaries.items()
            if is_check and (pid, False) in summaries]  # fmt: skip
