"""Each street's year as a Dask task; finished streets are kept, so a killed run resumes.

``run_streets`` submits one task per unfinished street (``street_year``: the street's whole year,
its response table run cell after cell inside the task) to a Dask distributed cluster: a
``LocalCluster`` of single-threaded worker processes on loopback by default, or the cluster
behind a scheduler address. Sensor models (``citysim.city.models``) are found or calibrated in
the client, once per camera key, and scattered to the workers once. The client alone writes:
the moment a task finishes, DIR/streets/<name>/task.json (the street's fingerprint, the worker,
its wall and CPU seconds and peak memory) and then DIR/streets/<name>/year.json (each written to
a temporary file and renamed, so a file is whole or absent). A street counts as finished when its
year.json is there and its task.json's fingerprint matches the street's job; a folder holding a
street of the same name with another fingerprint is refused (a different city or settings).
"""

from __future__ import annotations

import json
import logging
import os
import resource
import socket
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

from tqdm import tqdm

from citysim.city.models import city_models
from citysim.city.streets import StreetJob
from citysim.config.base import ScenarioError

#: How long to wait for a scheduler given by address before giving up, s.
SCHEDULER_TIMEOUT_S = 20.0


class CityRunError(ScenarioError):
    """A city run that cannot start or finish; the message names the folder, street or scheduler."""


def street_dir(out_dir: Path, name: str) -> Path:
    return Path(out_dir) / "streets" / name


def write_atomic(path: Path, text: str, tmp_dir: Path | None = None) -> None:
    """Write ``text`` to ``path`` through a temporary file and a rename: whole or absent. ``tmp_dir``
    (same file system; default ``path``'s folder) holds the temporary file, so a run killed while
    writing leaves nothing beside the outputs that the next run's folder check would refuse."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=tmp_dir or path.parent)
    with os.fdopen(fd, "w") as fh:
        fh.write(text)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # as an ordinary file would be, not mkstemp's owner-only mode
    os.replace(tmp, path)


def finished(out_dir: Path, job: StreetJob) -> bool:
    """Whether DIR holds this street's year from the same job; raises if it holds another job's."""
    folder = street_dir(out_dir, job.name)
    if not (folder / "year.json").exists():
        return False
    try:
        done = json.loads((folder / "task.json").read_text())["fingerprint"]
    except (OSError, ValueError, KeyError):
        return False  # a year without its task record is run again
    if done != job.fingerprint():
        raise CityRunError(f"--out: {folder} holds street {job.name!r} of a different city or settings (scenario, "
                           "site, costs, --controllers, --sample-s or fidelity changed); use a new output folder")
    return True


def street_year(job: StreetJob, sensor_model=None) -> tuple[dict, dict]:
    """The Dask task: one street's year (year.json's dict) and the task's facts (worker, times, memory)."""
    from citysim.year.plan import prepare_year
    from citysim.year.run import run_year

    wall0, cpu0 = time.perf_counter(), time.process_time()
    plan = prepare_year(job.scenario, job.year)
    with tempfile.TemporaryDirectory(prefix="citysim-street-") as tmp:
        result = run_year(plan, Path(tmp) / "year", list(job.controllers) if job.controllers else None, workers=1,
                          fidelity=job.fidelity, progress=False, scenario_file=job.source,
                          sensor_model=sensor_model)  # fmt: skip
    facts = {"street": job.name, "fingerprint": job.fingerprint(), "host": socket.gethostname(), "pid": os.getpid(),
             "wall_s": time.perf_counter() - wall0, "cpu_s": time.process_time() - cpu0, "finished_unix_s": time.time(),
             # ru_maxrss is KiB on Linux: the worker process's peak so far (flat across streets = no growth)
             "worker_peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}  # fmt: skip
    return result, facts


def connect(scheduler: str | None, workers: int | None):
    """(client, cluster or None): Client(scheduler) for an existing cluster, else a LocalCluster of
    ``workers`` single-threaded processes over TCP on 127.0.0.1."""
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            return Client(scheduler, timeout=f"{SCHEDULER_TIMEOUT_S}s"), None
        except (OSError, TimeoutError) as exc:
            raise CityRunError(f"--scheduler {scheduler!r}: cannot connect ({exc})") from None
    n = workers if workers is not None else max(1, min(2, os.cpu_count() or 1))
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                           protocol="tcp://", dashboard_address="127.0.0.1:0", silence_logs=logging.ERROR)  # fmt: skip
    return Client(cluster), cluster


def run_streets(jobs: Sequence[StreetJob], out_dir: Path, *, scheduler: str | None = None, workers: int | None = None,
                progress: bool = True, cache_dir: Path | None = None) -> dict[str, int]:  # fmt: skip
    """Run every unfinished street's year on Dask, writing each as it finishes; counts of streets.

    Parameters
    ----------
    jobs : the city's streets (``citysim.city.streets.prepare_streets``)
    out_dir : the city folder; DIR/streets/<name>/ receives each street's year.json and task.json
    scheduler : a Dask scheduler address (tcp://host:8786); None starts a local cluster
    workers : local cluster worker processes (default 2, or 1 on a one-core machine)
    progress : show a bar over streets (done, rate, time left)
    cache_dir : the sensor-model cache (default: the project's .cache/sensor_models)
    """
    from distributed import as_completed

    todo = [job for job in jobs if not finished(out_dir, job)]
    counts = {"streets": len(jobs), "skipped": len(jobs) - len(todo), "ran": 0}
    if not todo:
        return counts
    keys, models = city_models(todo, cache_dir, progress=progress)
    client, cluster = connect(scheduler, workers)
    bar = tqdm(total=len(jobs), initial=counts["skipped"], unit="street", disable=not progress, desc="streets")
    try:
        shared = {key: client.scatter(model, broadcast=True) for key, model in models.items()}
        futures = {client.submit(street_year, job, shared.get(keys.get(job.name)), pure=False): job for job in todo}
        for future in as_completed(futures):
            job = futures[future]
            result, facts = future.result()
            folder = street_dir(out_dir, job.name)
            write_atomic(folder / "task.json", json.dumps(facts, indent=2))
            write_atomic(folder / "year.json", json.dumps(result, indent=2))
            counts["ran"] += 1
            bar.set_postfix_str(job.name)
            bar.update(1)
    finally:
        bar.close()
        client.close()
        if cluster is not None:
            cluster.close()
    return counts
