"""A pool's workers end with the process that started them, even one killed with SIGKILL, and at
once when it leaves the pool's block by an exception (SIGTERM under exit_on_terminate)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[3]

# a parent that starts a pool of two workers, each sleeping an hour in a task, prints their pids and waits
PARENT = """
import os, sys, time
from citysim.sim.workers import spawn_pool

def task(_):
    time.sleep(3600)

if __name__ == "__main__":
    with spawn_pool(2) as pool:
        for f in [pool.submit(task, i) for i in range(2)]:
            pass
        time.sleep(2.0)  # both workers started and busy
        print(" ".join(str(p) for p in pool._processes), flush=True)  # the pool's worker pids (CPython)
        time.sleep(3600)
"""

# the same parent, SIGTERM turned into an exit inside the pool's block
TERMINATED_PARENT = PARENT.replace(
    "    with spawn_pool(2) as pool:",
    "    from detector.outdir import exit_on_terminate\n"
    "    with exit_on_terminate(), spawn_pool(2) as pool:",
)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a zombie is dead but not yet reaped by its new parent
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().split(") ")[1][0] != "Z"
    except FileNotFoundError:
        return False


def _start(tmp_path, source: str) -> tuple[subprocess.Popen, list[int]]:
    script = tmp_path / "parent.py"
    script.write_text(source)
    parent = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True, cwd=REPO)
    workers = [int(p) for p in parent.stdout.readline().split()]
    assert len(workers) == 2 and all(_alive(p) for p in workers)
    return parent, workers


def _all_gone(workers: list[int], within_s: float) -> bool:
    deadline = time.monotonic() + within_s
    while time.monotonic() < deadline and any(_alive(p) for p in workers):
        time.sleep(0.1)
    return not any(_alive(p) for p in workers)


def test_workers_exit_once_their_parent_is_killed(tmp_path):
    parent, workers = _start(tmp_path, PARENT)
    try:
        os.kill(parent.pid, signal.SIGKILL)  # no handler, no pool shutdown
        parent.wait()
        assert _all_gone(workers, 10.0), "a worker outlived its parent"
    finally:
        parent.kill()


def test_a_terminated_parent_does_not_wait_for_its_workers_tasks(tmp_path):
    parent, workers = _start(tmp_path, TERMINATED_PARENT)
    try:
        os.kill(parent.pid, signal.SIGTERM)
        # the tasks sleep an hour: a pool that waited for them would still be running (TimeoutExpired)
        assert parent.wait(timeout=120) == 143
        assert _all_gone(workers, 10.0), "a worker outlived its stopped parent"
    finally:
        parent.kill()
